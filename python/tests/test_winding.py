"""Winding-number signs (sign="winding") on open and self-intersecting meshes, against a NumPy
sum of every triangle's solid angle (Van Oosterom and Strackee), and the refusals of
pseudonormal signs that point to them."""

import numpy as np
import pytest

import delta


def exact_winding_numbers(mesh, points):
    """The generalized winding number at every point: the sum over all triangles of their solid
    angles over 4 pi."""
    v = np.asarray(mesh.vertices)[np.asarray(mesh.triangles)]  # (m, 3, 3)
    result = np.empty(len(points))
    for i, p in enumerate(points):
        a, b, c = (v[:, k, :] - p for k in range(3))
        la, lb, lc = (np.linalg.norm(x, axis=1) for x in (a, b, c))
        numerator = np.einsum("ij,ij->i", a, np.cross(b, c))
        denominator = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc
                       + np.einsum("ij,ij->i", a, c) * lb + np.einsum("ij,ij->i", b, c) * la)
        result[i] = np.sum(2.0 * np.arctan2(numerator, denominator)) / (4.0 * np.pi)
    return result


def cut_hole(mesh, radius):
    """`mesh` less its triangles whose centroid lies within `radius` of triangle 0's."""
    vertices, triangles = np.asarray(mesh.vertices), np.asarray(mesh.triangles)
    centroids = vertices[triangles].mean(axis=1)
    kept = np.linalg.norm(centroids - centroids[0], axis=1) > radius
    return delta.Mesh(vertices, triangles[kept])


def near_points(mesh, count, reach, seed):
    rng = np.random.default_rng(seed)
    vertices = np.asarray(mesh.vertices)
    picked = vertices[rng.integers(0, len(vertices), count)]
    return picked + rng.uniform(-reach, reach, (count, 3))


def test_open_mesh_signs_equal_the_exact_winding_number():
    open_sphere = cut_hole(delta.icosphere(3), 0.4)
    assert not open_sphere.closed
    points = np.vstack([near_points(open_sphere, 1500, 0.1, 1),
                        np.random.default_rng(2).uniform(-1.5, 1.5, (500, 3))])
    r = delta.distance(open_sphere, points, sign="winding")
    w = exact_winding_numbers(open_sphere, points)
    off = r["distance"] > 0
    certain = off & (np.abs(w - 0.5) > 1e-9)
    np.testing.assert_array_equal(r["inside"][certain], (w > 0.5)[certain])
    clear = off & (np.abs(np.abs(w - 0.5) - 0.05) > 1e-9)
    np.testing.assert_array_equal(r["ambiguous"][clear], (np.abs(w - 0.5) <= 0.05)[clear])
    assert r.dtype == delta.distance_dtype and "ambiguous" in r.dtype.names


def test_pseudonormal_signs_refuse_open_meshes_and_name_the_winding_sign():
    open_sphere = cut_hole(delta.icosphere(2), 0.3)
    with pytest.raises(delta.Error, match='sign="winding"'):
        delta.distance(open_sphere, np.zeros((1, 3)), signed=True)
    r = delta.distance(open_sphere, np.zeros((1, 3)), signed=True, sign="winding")
    assert r["inside"][0] and not r["ambiguous"][0]
    # sign implies signed
    assert delta.distance(open_sphere, np.zeros((1, 3)), sign="winding")["inside"][0]


def test_a_wrong_sign_is_a_value_error():
    with pytest.raises(ValueError, match="winding"):
        delta.distance(delta.icosphere(1), np.zeros((1, 3)), signed=True, sign="ray")
    with pytest.raises(ValueError):
        delta.ib.AdaptiveGrid(delta.icosphere(1), levels=3, sign="Winding")


def test_self_intersections_refuse_pseudonormals():
    sphere = delta.icosphere(2)
    vertices = np.array(sphere.vertices)
    vertices[0] *= -1.3  # pushed through the sphere: closed, crossing itself
    crossing = delta.Mesh(vertices, np.asarray(sphere.triangles))
    query = delta.QueryMesh(crossing)
    assert crossing.closed and query.self_intersections > 0
    assert delta.QueryMesh(sphere).self_intersections == 0
    with pytest.raises(delta.Error, match="crosses itself"):
        delta.distance(query, np.zeros((1, 3)), signed=True)
    points = np.random.default_rng(3).uniform(-1.4, 1.4, (400, 3))
    r = delta.distance(query, points, sign="winding")
    w = exact_winding_numbers(crossing, points)
    certain = (r["distance"] > 0) & (np.abs(w - 0.5) > 1e-9)
    np.testing.assert_array_equal(r["inside"][certain], (w > 0.5)[certain])


def test_closed_meshes_sign_alike_both_ways():
    sphere = delta.icosphere(3)
    points = np.random.default_rng(4).uniform(-1.3, 1.3, (2000, 3))
    pseudonormal = delta.distance(sphere, points, signed=True)
    winding = delta.distance(sphere, points, sign="winding")
    np.testing.assert_array_equal(pseudonormal["inside"], winding["inside"])
    assert not winding["ambiguous"].any() and not pseudonormal["ambiguous"].any()


def test_ib_grid_of_an_open_boundary():
    open_sphere = cut_hole(delta.icosphere(3), 0.3)
    with pytest.raises(delta.Error, match="winding"):
        delta.ib.AdaptiveGrid(open_sphere, levels=4)
    grid = delta.ib.AdaptiveGrid(open_sphere, levels=4, sign="winding")
    assert (grid.distances < 0).any() and (grid.distances > 0).any()
    # a move re-signs every vertex: the same as a new grid around the moved boundary
    motion = delta.RigidTransform(delta.Quaternion.from_axis_angle([0, 0, 1], 0.4), [0.05, 0, 0])
    grid.move_boundary(motion)
    moved = delta.QueryMesh(open_sphere)
    moved.transform(motion)
    fresh = delta.ib.AdaptiveGrid(moved, levels=4, sign="winding", domain=grid.domain)
    assert grid.leaves_per_level.tolist() == fresh.leaves_per_level.tolist()
    np.testing.assert_array_equal(np.sort(grid.distances), np.sort(fresh.distances))


def test_real_open_mesh(meshes):
    dragon = delta.load(meshes / "ChineseDragon-10kv.off")
    assert not dragon.closed
    rng = np.random.default_rng(5)
    diagonal = np.linalg.norm(np.diff(np.asarray(dragon.bounds), axis=0))
    points = near_points(dragon, 300, 0.01 * diagonal, 6)
    r = delta.distance(dragon, points, sign="winding")
    w = exact_winding_numbers(dragon, points)
    certain = (r["distance"] > 0) & (np.abs(w - 0.5) > 1e-9)
    np.testing.assert_array_equal(r["inside"][certain], (w > 0.5)[certain])
    del rng


def test_parts_that_do_not_nest_refuse_pseudonormals_and_sign_by_winding_number():
    # A ball with a second, smaller shell of the same orientation inside it: closed, crossing
    # nowhere, winding number 2 inside the inner shell and 1 between them.
    outer, inner = delta.icosphere(2, radius=2.0), delta.icosphere(2)
    vertices = np.vstack([np.asarray(outer.vertices), np.asarray(inner.vertices)])
    triangles = np.vstack([np.asarray(outer.triangles),
                           np.asarray(inner.triangles) + len(np.asarray(outer.vertices))])
    shells = delta.Mesh(vertices, triangles)
    query = delta.QueryMesh(shells)
    assert shells.closed and query.self_intersections == 0
    nesting = query.part_nesting
    assert nesting["parts"] == 2 and nesting["misoriented"] == 1 and nesting["pinched"] == 0
    assert nesting["misoriented_triangles"] == [len(np.asarray(outer.triangles))]
    assert not query.bounds_solid
    assert delta.QueryMesh(outer).part_nesting["misoriented"] == 0
    assert delta.QueryMesh(outer).bounds_solid
    with pytest.raises(delta.Error, match="1 of its 2 parts is oriented against"):
        delta.distance(query, np.zeros((1, 3)), signed=True)
    points = np.random.default_rng(5).uniform(-2.4, 2.4, (400, 3))
    r = delta.distance(query, points, sign="winding")
    w = exact_winding_numbers(shells, points)
    certain = r["distance"] > 1e-6
    np.testing.assert_array_equal(r["inside"][certain], (w > 0.5)[certain])
    assert r["inside"][certain & (np.linalg.norm(points, axis=1) < 0.9)].all()
    # Reversing the inner shell makes it a cavity: a solid, signed alike both ways.
    cavity = delta.Mesh(vertices, np.vstack([np.asarray(outer.triangles),
                                             np.asarray(inner.triangles)[:, ::-1]
                                             + len(np.asarray(outer.vertices))]))
    assert delta.QueryMesh(cavity).bounds_solid
    np.testing.assert_array_equal(delta.distance(cavity, points, signed=True)["inside"],
                                  delta.distance(cavity, points, sign="winding")["inside"])
