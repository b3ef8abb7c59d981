"""Queries release the global interpreter lock: while one Python thread runs a long query, the
main thread keeps running Python code, and the threaded answers equal the serial ones."""

import concurrent.futures
import sys
import threading
import time

import numpy as np
import pytest

import delta

POINTS = 100_000  # about half a second of queries against the armadillo on two cores


@pytest.fixture(scope="module")
def armadillo(meshes):
    return delta.QueryMesh(delta.load(meshes / "armadillo.off"))


@pytest.fixture(scope="module")
def points(armadillo):
    lower, upper = armadillo.bounds
    return lower + (upper - lower) * np.random.default_rng(7).random((POINTS, 3))


@pytest.fixture(scope="module")
def serial(armadillo, points):
    return delta.distance(armadillo, points, signed=True)


def count_during(query):
    """Runs query() in another thread; returns its result, its duration and how many times the
    main thread went round a loop of Python code while it ran (the worker reads the count just
    before and just after the call)."""
    count = [0]
    result = {}

    def work():
        before, start = count[0], time.perf_counter()
        value = query()
        seconds, rounds = time.perf_counter() - start, count[0] - before
        result.update(value=value, seconds=seconds, rounds=rounds)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-4)
    try:
        thread = threading.Thread(target=work)
        thread.start()
        while thread.is_alive():
            count[0] += 1
        thread.join()
    finally:
        sys.setswitchinterval(interval)
    return result["value"], result["seconds"], result["rounds"]


def assert_ran_alongside(query):
    """The main thread kept running during query(): at least 5% of the rounds it makes in the
    same time beside a thread that sleeps (which releases the GIL). Measured on two cores, where
    the query's OpenMP threads take both: about 30% when the query releases the GIL, 0.4 to 0.6%
    when it holds it (the loop then runs only in the switch intervals, 0.1 ms each here, before
    and after the call). Returns the query's result."""
    _, idle_seconds, idle_rounds = count_during(lambda: time.sleep(0.2))
    value, seconds, rounds = count_during(query)
    expected = idle_rounds / idle_seconds * seconds
    print(f"{rounds} rounds of the main thread during a {seconds:.2f} s query ({expected:.0f} idle)")
    assert rounds >= max(0.05 * expected, 10_000), "the query held the GIL"
    return value


def test_distance_releases_the_gil(armadillo, points, serial):
    threaded = assert_ran_alongside(lambda: delta.distance(armadillo, points, signed=True))
    np.testing.assert_array_equal(threaded, serial)


def test_contacts_release_the_gil(meshes):
    first = delta.QueryMesh(delta.load(meshes / "armadillo.off"))
    second = first.copy().transform(
        delta.RigidTransform(delta.Quaternion.from_axis_angle((0, 0, 1), 0.05), (1.0, 0.0, 0.0))
    )
    serial = delta.contacts(first, second, 0.3)
    threaded = assert_ran_alongside(lambda: delta.contacts(first, second, 0.3))
    np.testing.assert_array_equal(threaded, serial)


def test_python_threads_query_side_by_side(armadillo, points, serial):
    quarters = np.array_split(points, 4)
    with concurrent.futures.ThreadPoolExecutor(max_workers=2) as pool:
        parts = list(pool.map(lambda part: delta.distance(armadillo, part, signed=True), quarters))
    np.testing.assert_array_equal(np.concatenate(parts), serial)
