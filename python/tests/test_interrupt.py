"""Ctrl-C stops a long points query or grid build within a fraction of a second, with nothing
left half-written: the main thread starts the call, a timer thread sends SIGINT to it, and the
KeyboardInterrupt must arrive soon after, long before the call would have ended.

Each long call is sized from a short calibration run to take at least 5 s on the machine at hand
(several times that on a loaded two-core CI machine), and the interrupt stops it at about 0.3 s,
so the tests themselves run in about a second each. The bound on the delay, 1 s, is generous:
measured on two shared cores, the median is some tens of milliseconds.
"""

import signal
import threading
import time

import numpy as np
import pytest

import delta

SIGNAL_AFTER = 0.3  # seconds into the call
LATENCY_BOUND = 1.0  # seconds from the signal to KeyboardInterrupt
LONG_CALL = 5.0  # seconds the call would take without the interrupt, at least


def interrupt(call):
    """Runs call() on the main thread, sending it SIGINT after SIGNAL_AFTER seconds; returns the
    seconds from the signal to the KeyboardInterrupt (fails if the call ends without one)."""
    assert threading.current_thread() is threading.main_thread()
    sent = []

    def send():
        sent.append(time.perf_counter())
        signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    timer = threading.Timer(SIGNAL_AFTER, send)
    start = time.perf_counter()
    timer.start()
    try:
        call()
    except KeyboardInterrupt:
        caught = time.perf_counter()
    else:
        pytest.fail(f"the call ran to its end ({time.perf_counter() - start:.2f} s) uninterrupted")
    finally:
        timer.join()
    return caught - sent[0]


@pytest.fixture(autouse=True)
def default_sigint_handler():
    """SIGINT raises KeyboardInterrupt (pytest keeps Python's default handler, but be sure)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


def test_ctrl_c_stops_a_long_points_query_and_leaves_out_unchanged():
    # Points at the centre of a sphere: every triangle is about as near, so each search visits
    # most of the tree (about 10 µs a point on one core): many chunks, each short.
    mesh = delta.QueryMesh(delta.icosphere(3))
    start = time.perf_counter()
    delta.distance(mesh, np.zeros((2000, 3)))
    per_point = (time.perf_counter() - start) / 2000
    count = int(LONG_CALL / per_point) + 1
    points = np.zeros((count, 3))
    out = np.zeros(count, delta.distance_dtype)
    out["distance"] = -1.0
    before = out.copy()
    latency = interrupt(lambda: delta.distance(mesh, points, out=out))
    print(f"KeyboardInterrupt {latency * 1000:.0f} ms after SIGINT ({count} points)")
    assert latency < LATENCY_BOUND
    np.testing.assert_array_equal(out, before)  # not half-written
    # The mesh answers as before afterwards.
    again = delta.distance(mesh, points[:1000])
    np.testing.assert_array_equal(again["distance"], delta.distance(mesh, [[0, 0, 0]])["distance"][0])


def test_ctrl_c_stops_point_contacts():
    mesh = delta.QueryMesh(delta.icosphere(3))
    start = time.perf_counter()
    delta.point_contacts(mesh, np.zeros((2000, 3)), 2.0)
    count = int(LONG_CALL / ((time.perf_counter() - start) / 2000)) + 1
    latency = interrupt(lambda: delta.point_contacts(mesh, np.zeros((count, 3)), 2.0))
    assert latency < LATENCY_BOUND


def test_ctrl_c_stops_a_grid_build():
    # A grid refined around a sphere has about four times the cells with each level more.
    sphere = delta.QueryMesh(delta.icosphere(4))
    start = time.perf_counter()
    delta.ib.AdaptiveGrid(sphere, levels=6)
    seconds, levels = time.perf_counter() - start, 6
    while seconds < LONG_CALL and levels < 11:
        seconds, levels = 4 * seconds, levels + 1
    latency = interrupt(lambda: delta.ib.AdaptiveGrid(sphere, levels=levels))
    print(f"KeyboardInterrupt {latency * 1000:.0f} ms after SIGINT (levels {levels})")
    assert latency < LATENCY_BOUND
    # Builds work again afterwards.
    assert delta.ib.AdaptiveGrid(sphere, levels=3).levels == 3


def test_a_query_on_another_thread_runs_to_its_end():
    # Python runs signal handlers on the main thread only: the KeyboardInterrupt goes there, and
    # a worker thread's query (which does not look for signals) finishes with every answer.
    mesh = delta.QueryMesh(delta.icosphere(3))
    start = time.perf_counter()
    delta.distance(mesh, np.zeros((2000, 3)))
    count = int(1.0 / ((time.perf_counter() - start) / 2000)) + 1  # about a second
    points = np.zeros((count, 3))
    results = []
    worker = threading.Thread(target=lambda: results.append(delta.distance(mesh, points)))
    worker.start()

    def wait():
        while worker.is_alive():
            time.sleep(0.005)

    latency = interrupt(wait)
    while worker.is_alive():
        time.sleep(0.01)
    worker.join()
    assert latency < LATENCY_BOUND
    assert len(results) == 1 and results[0].shape == (count,)
    np.testing.assert_array_equal(results[0]["distance"], results[0]["distance"][0])
    assert (results[0]["triangle"] != delta.NO_TRIANGLE).all()
