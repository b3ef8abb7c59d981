"""Contacts, distances, the filter and the minimum distance, compared bit for bit with the C++
command-line tool's output for the same meshes and points (`delta contact`, `delta distance`)."""

import math
import tracemalloc

import numpy as np
import pytest

import delta
from conftest import read_csv, write_xyz

# B is fandisk turned 20 degrees about (1, 1, 0) through its box centre, then moved.
ROTATE_B = "1,1,0,20"
TRANSLATE_B = (0.05, 0.0, 0.0)
EPS = 0.005


def moved_b(mesh, translation=TRANSLATE_B):
    """What `--rotate-b 1,1,0,20 --translate-b X,Y,Z` makes of B, with the same arithmetic."""
    lower, upper = mesh.bounds
    return mesh.copy().rotate((1, 1, 0), 20 * math.pi / 180, pivot=(lower + upper) * 0.5).translate(
        translation
    )


def cli_contacts(cli, tmp_path, meshes, *options):
    out = tmp_path / "contacts.csv"
    path = meshes / "fandisk.off"
    cli("contact", path, path, "--rotate-b", ROTATE_B, "--translate-b", "0.05,0,0", "--eps", EPS,
        "--out", out, *options)
    return read_csv(out)


def assert_same_contacts(found, rows):
    assert len(found) == len(rows) > 100
    column = lambda *names: np.array([[float(row[n]) for n in names] for row in rows])
    np.testing.assert_array_equal(found["triangle_a"], [int(row["triangle_a"]) for row in rows])
    np.testing.assert_array_equal(found["triangle_b"], [int(row["triangle_b"]) for row in rows])
    np.testing.assert_array_equal(found["x"], column("x", "y", "z"))
    np.testing.assert_array_equal(found["normal"], column("normal_x", "normal_y", "normal_z"))
    np.testing.assert_array_equal(found["distance"], column("distance")[:, 0])
    np.testing.assert_array_equal(found["overlap"], [row["overlap"] == "1" for row in rows])


@pytest.mark.parametrize("method", ["hybrid", "bruteforce", "penalty"])
def test_contacts_equal_the_cli(fandisk, cli, tmp_path, meshes, method):
    found = delta.contacts(fandisk, moved_b(fandisk), EPS, method=method)
    assert found.dtype == delta.contact_dtype and found.ndim == 1
    assert_same_contacts(found, cli_contacts(cli, tmp_path, meshes, "--method", method))
    # Every field is what the docstring says.
    np.testing.assert_allclose(np.linalg.norm(found["normal"], axis=1), found["distance"] / 2,
                               rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(found["direction"], axis=1), 1.0, rtol=1e-12)
    assert (found["distance"] < 2 * EPS).all()


def test_filter_equals_the_cli(fandisk, cli, tmp_path, meshes):
    found = delta.contacts(delta.QueryMesh(fandisk), delta.QueryMesh(moved_b(fandisk)), EPS)
    kept = delta.filter(found, 0.02)
    assert 0 < len(kept) < len(found)
    assert_same_contacts(kept, cli_contacts(cli, tmp_path, meshes, "--filter", 0.02))
    # Any structured array with the fields works, whatever its layout: here a view with the
    # fields in another order.
    reordered = found[["triangle_b", "x", "normal", "direction", "distance", "overlap", "triangle_a"]]
    np.testing.assert_array_equal(delta.filter(reordered, 0.02), kept)


def test_minimum_distance_equals_the_cli(fandisk, cli_json, meshes):
    path = meshes / "fandisk.off"
    closest = delta.minimum_distance(fandisk, moved_b(fandisk, (1.2, 0.0, 0.0)))
    expected = cli_json("contact", path, path, "--rotate-b", ROTATE_B, "--translate-b", "1.2,0,0")
    assert closest.distance == expected["min_distance"] > 0
    assert (closest.triangle_a, closest.triangle_b) == (expected["triangle_a"], expected["triangle_b"])
    assert closest.intersect == expected["intersect"]
    assert np.linalg.norm(closest.p - closest.q) == pytest.approx(closest.distance, rel=1e-12)


def test_mesh_and_query_mesh_give_the_same_contacts(fandisk):
    b = moved_b(fandisk)
    by_mesh = delta.contacts(fandisk, b, EPS)
    by_query_mesh = delta.contacts(delta.QueryMesh(fandisk), delta.QueryMesh(b), EPS)
    np.testing.assert_array_equal(by_mesh, by_query_mesh)
    assert not by_mesh.flags.owndata  # Δ's own buffer, handed over without a copy
    assert delta.contacts(fandisk, b.copy().translate((5, 0, 0)), EPS).shape == (0,)


def points_around(mesh, count, rng):
    lower, upper = mesh.bounds
    margin = 0.1 * (upper - lower)
    return lower - margin + (upper - lower + 2 * margin) * rng.random((count, 3))


@pytest.mark.parametrize("options", [(), ("--signed",), ("--eps", 0.05), ("--eps", 0.05, "--signed")])
def test_distance_equals_the_cli(fandisk, cli, tmp_path, meshes, rng, options):
    points = points_around(fandisk, 3000, rng)
    points[:3] = fandisk.vertices[:3]  # on the surface
    write_xyz(points, tmp_path / "points.xyz")
    cli("distance", meshes / "fandisk.off", "--points", tmp_path / "points.xyz", "--out",
        tmp_path / "d.csv", "--quiet", *options)
    rows = read_csv(tmp_path / "d.csv")
    signed = "--signed" in options
    eps = options[options.index("--eps") + 1] if "--eps" in options else None
    result = delta.distance(fandisk, points, eps=eps, signed=signed)
    assert result.dtype == delta.distance_dtype and result.shape == (3000,)
    found = np.array([row["distance"] != "" for row in rows])
    assert found.all() if eps is None else 0 < found.sum() < len(found)
    np.testing.assert_array_equal(result["distance"][~found], np.inf)
    np.testing.assert_array_equal(result["triangle"][~found], delta.NO_TRIANGLE)
    rows = [row for row in rows if row["distance"] != ""]
    answered = result[found]
    np.testing.assert_array_equal(answered["distance"], [float(row["distance"]) for row in rows])
    np.testing.assert_array_equal(
        answered["closest"],
        [[float(row[f"closest_{axis}"]) for axis in "xyz"] for row in rows],
    )
    np.testing.assert_array_equal(answered["triangle"], [int(row["triangle"]) for row in rows])
    if signed:
        np.testing.assert_array_equal(answered["inside"], [row["inside"] == "1" for row in rows])
        assert 0 < answered["inside"].sum() < len(answered)
        signed_distance = delta.signed_distance(result)
        np.testing.assert_array_equal(signed_distance < 0, result["inside"])
    assert result["distance"][:3].tolist() == [0.0, 0.0, 0.0]


def test_distance_keeps_the_points_shape(fandisk, rng):
    points = points_around(fandisk, 24, rng)
    flat = delta.distance(fandisk, points)
    grid = delta.distance(fandisk, points.reshape(2, 3, 4, 3))
    assert grid.shape == (2, 3, 4)
    np.testing.assert_array_equal(grid.reshape(-1), flat)
    single = delta.distance(fandisk, points[0])
    assert single.shape == () and single["distance"] == flat[0]["distance"]
    assert delta.distance(fandisk, np.zeros((0, 3))).shape == (0,)


def test_distance_writes_into_out_without_copying_the_points(fandisk, rng):
    mesh = delta.QueryMesh(fandisk)
    points = points_around(fandisk, 40_000, rng)
    out = np.empty(len(points), dtype=delta.distance_dtype)
    expected = delta.distance(mesh, points)
    # The answers go straight into `out`; the points are read where they are.
    tracemalloc.start()
    result = delta.distance(mesh, points, out=out)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert np.shares_memory(result, out)
    np.testing.assert_array_equal(out, expected)
    assert peak < points.nbytes // 10, f"{peak} bytes allocated: the points were copied"
    # The check can fail: float32 points must be converted, a float64 copy the size of points.
    as_float32 = points.astype(np.float32)
    tracemalloc.start()
    delta.distance(mesh, as_float32, out=out)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak >= points.nbytes
    # Without `out`, one allocation: the result.
    tracemalloc.start()
    delta.distance(mesh, points)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < out.nbytes + points.nbytes // 10


def test_distance_records_are_the_same_bytes_every_time(fandisk, rng):
    # The records' two padding bytes were left as the queries' struct copies found them, so
    # tobytes() (and a hash of it) differed from run to run for the same answers.
    mesh = delta.QueryMesh(fandisk)
    points = points_around(fandisk, 5_000, rng)
    expected = delta.distance(mesh, points, signed=True).tobytes()
    for _ in range(3):
        out = np.empty(len(points), dtype=delta.distance_dtype)
        out.view(np.uint8)[:] = 0xAB  # what the padding held before
        delta.distance(mesh, points, signed=True, out=out)
        assert out.tobytes() == expected
        assert delta.distance(mesh, points, signed=True).tobytes() == expected
    padding = np.frombuffer(expected, np.uint8).reshape(len(points), -1)[:, 38:]
    assert padding.shape[1] == delta.distance_dtype.itemsize - 38 and not padding.any()


def test_moved_query_mesh_answers_where_it_is(fandisk, rng):
    motion = delta.RigidTransform(delta.Quaternion.from_axis_angle((0, 1, 1), 0.4), (0.3, -0.2, 0.1))
    prepared = delta.QueryMesh(fandisk)
    moved = prepared.copy()
    assert moved.transform(motion) is moved  # chains, like Mesh transforms
    assert moved.moved and not prepared.moved
    points = points_around(fandisk, 500, rng)
    direct = delta.distance(fandisk.copy().transform(motion), points, signed=True)
    by_pose = delta.distance(moved, points, signed=True)
    np.testing.assert_allclose(by_pose["distance"], direct["distance"], rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(by_pose["inside"], direct["inside"])
    np.testing.assert_allclose(moved.set_pose(delta.RigidTransform()).pose.matrix, np.eye(4))
    np.testing.assert_array_equal(delta.distance(moved, points), delta.distance(prepared, points))


def test_point_contacts_are_the_points_within_eps(fandisk, rng):
    points = points_around(fandisk, 2000, rng)
    near = delta.distance(fandisk, points, signed=True)
    found = delta.point_contacts(fandisk, points, 0.05)
    within = np.flatnonzero(near["distance"] < 0.05)
    np.testing.assert_array_equal(found["triangle_a"], within)
    np.testing.assert_array_equal(found["triangle_b"], near["triangle"][within])
    np.testing.assert_array_equal(found["distance"], near["distance"][within])
    np.testing.assert_array_equal(found["overlap"], near["inside"][within])


def test_bad_queries_raise_delta_error(fandisk):
    quad = delta.quad()
    with pytest.raises(delta.Error, match="epsilon"):
        delta.contacts(fandisk, fandisk, -0.1)
    with pytest.raises(delta.Error):
        delta.contacts(fandisk, fandisk, float("nan"))
    with pytest.raises(delta.Error, match="method 'newton'"):
        delta.contacts(fandisk, fandisk, 0.1, method="newton")
    with pytest.raises(delta.Error, match="epsilon"):
        delta.distance(fandisk, [[0, 0, 0]], eps=-1.0)
    with pytest.raises(delta.Error, match="epsilon"):
        delta.distance(fandisk, [[0, 0, 0]], eps=0.0)
    with pytest.raises(delta.Error, match="closed"):
        delta.distance(quad, [[0, 0, 1]], signed=True)
    with pytest.raises(delta.Error, match="1"):
        delta.distance(fandisk, [[0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(delta.Error, match="shape"):
        delta.distance(fandisk, np.zeros((5, 2)))
    with pytest.raises(TypeError, match="real numbers"):
        delta.distance(fandisk, np.zeros((5, 3), dtype=complex))
    with pytest.raises(TypeError, match="dtype"):
        delta.distance(fandisk, np.zeros((5, 3)), out=np.empty(5))
    with pytest.raises(delta.Error, match="shape"):
        delta.distance(fandisk, np.zeros((5, 3)), out=np.empty(4, dtype=delta.distance_dtype))
    with pytest.raises(delta.Error, match="h"):
        delta.filter(delta.contacts(fandisk, moved_b(fandisk), EPS), -1.0)
    with pytest.raises(delta.Error, match="field 'normal'"):
        delta.filter(np.zeros(3, dtype=[("x", "f8", 3)]), 0.1)
    scalar_normals = [(n, "f8", 3) for n in ("x", "direction")] + [("normal", "f8")]
    with pytest.raises(delta.Error, match="'normal' must hold 3"):
        delta.filter(np.zeros(3, dtype=scalar_normals + [("distance", "f8"), ("overlap", "?"),
                                                          ("triangle_a", "u4"), ("triangle_b", "u4")]), 0.1)
    with pytest.raises(TypeError):
        delta.contacts(fandisk, "fandisk.off", 0.1)


def test_signed_distance_takes_only_a_distance_result():
    # An array of points was an IndexError from inside NumPy.
    result = delta.distance(delta.box(), np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]), signed=True)
    assert delta.signed_distance(result).tolist() == [-0.5, 1.5]
    assert delta.signed_distance(result[1]) == 1.5
    for wrong in (np.zeros(3), [1, 2], None):
        with pytest.raises(TypeError, match="distance_dtype"):
            delta.signed_distance(wrong)
