"""Coordinates over the whole double range (issue 21, "Far coordinates"): a query either answers
correctly or raises delta.Error (a ValueError) naming the point or mesh and the supported range,
never a crash of the interpreter and never inf or NaN as an answer."""

import math

import numpy as np
import pytest

import delta

TETRA_V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=float)
TETRA_T = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])


@pytest.mark.parametrize("signed", [False, True])
@pytest.mark.parametrize("eps", [None, 0.5])
def test_distance_of_a_far_point_raises(signed, eps):
    mesh = delta.QueryMesh(delta.granulate(1))
    with pytest.raises(ValueError, match=r"point 0 .*±2\^200"):
        delta.distance(mesh, np.array([[1e155, 0.0, 0.0]]), eps=eps, signed=signed)
    many = np.full((5000, 3), 0.1)
    many[4321] = (0.0, -1e300, 0.0)
    with pytest.raises(delta.Error, match="point 4321 "):
        delta.distance(mesh, many, eps=eps, signed=signed)


def test_point_contacts_of_a_far_point_raise():
    with pytest.raises(ValueError, match=r"point 0 .*±2\^200"):
        delta.point_contacts(delta.granulate(1), np.array([[1e155, 0.0, 0.0]]), 0.5)


def test_points_at_the_ranges_edge_answer_finitely():
    r = delta.distance(delta.granulate(2), np.array([[1e60, 0.0, 0.0], [-1e60, 1e60, 1.0]]))
    assert np.all(np.isfinite(r["distance"]))
    assert r["distance"][0] == pytest.approx(1e60, rel=1e-12)


def test_minimum_distance_of_meshes_scaled_by_1e300_raises():
    huge = delta.granulate(4).scale(1e300)
    with pytest.raises(ValueError, match=r"±2\^200"):
        delta.minimum_distance(huge, huge)
    with pytest.raises(ValueError, match=r"±2\^200"):
        delta.contacts(huge, delta.granulate(5), 0.1)


def test_far_apart_tetrahedra_are_refused_not_intersecting():
    a = delta.Mesh(TETRA_V * 3e38, TETRA_T)
    b = delta.Mesh(TETRA_V * 3e38 + (1e300, 0, 0), TETRA_T)
    with pytest.raises(ValueError, match=r"1\.0+1e\+300.*±2\^200"):
        delta.minimum_distance(a, b)
    c = delta.Mesh(TETRA_V * 3e38 + (1e50, 0, 0), TETRA_T)
    d = delta.minimum_distance(a, c)
    assert not d.intersect
    assert d.distance == pytest.approx(1e50 - 3e38, rel=1e-12)


def test_moved_query_mesh_is_checked_where_it_is():
    b = delta.QueryMesh(delta.granulate(7))
    b.transform(delta.RigidTransform.translation_by((1e155, 0, 0)))
    with pytest.raises(ValueError, match="second mesh"):
        delta.minimum_distance(delta.QueryMesh(delta.granulate(6)), b)


def test_volume_of_a_mesh_scaled_by_1e300_raises_not_nan():
    with pytest.raises(ValueError, match="overflows"):
        delta.Mesh(TETRA_V * 1e300, TETRA_T).volume
    with pytest.raises(ValueError, match="overflows"):
        delta.Mesh(TETRA_V * 1e300, TETRA_T).area
    # Scaled by a power of two, exactly scaled answers where plain products overflowed.
    sphere = delta.icosphere(2)
    big = delta.icosphere(2).scale(2.0**400)
    assert big.area == math.ldexp(sphere.area, 800)
    assert abs(delta.Mesh(TETRA_V * 2.0**300, TETRA_T).volume) == math.ldexp(1 / 6, 900)


def test_tiny_meshes_are_refused_tiny_gaps_measured():
    with pytest.raises(ValueError, match=r"2\^-200"):
        delta.QueryMesh(delta.Mesh(TETRA_V * 1e-300, TETRA_T))
    # A tetrahedron of size 1e-300 beside one of size 1: a point 1e-301 off the small one's face.
    vertices = np.vstack([TETRA_V * 1e-300, TETRA_V + 2.0])
    triangles = np.vstack([TETRA_T, TETRA_T + 4])
    mesh = delta.QueryMesh(delta.Mesh(vertices, triangles))
    points = np.array([[0.25e-300, 0.25e-300, -1e-301], [0.25e-300, 0.25e-300, 1e-301]])
    r = delta.distance(mesh, points, signed=True)
    assert list(r["distance"]) == [1e-301, 1e-301]
    assert list(r["inside"]) == [False, True]
