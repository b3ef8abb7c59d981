"""delta.overlap: the solid two closed meshes share (A ∩ B), its integrals per region and in all,
and the curves where the surfaces cross; checked against boxes worked by hand, the spherical lens,
a Monte Carlo estimate by Δ's own inside tests, and the `delta overlap` tool."""

import math

import numpy as np
import pytest

import delta

OFFSET = (0.5, 0.25, 0.125)
# A = [-0.5, 0.5]^3 and B = A + OFFSET share the box [0, 0.5] x [-0.25, 0.5] x [-0.375, 0.5]; the
# part of A's surface inside B is its three upper faces' parts in that box; the intersection curve
# is the hexagon of the box's edges where a face of A meets a face of B.
CUBES_VOLUME = 0.5 * 0.75 * 0.875
CUBES_CENTROID = (0.25, 0.125, 0.0625)
CUBES_AREA_VECTOR = (0.75 * 0.875, 0.5 * 0.875, 0.5 * 0.75)
CUBES_CURVE_LENGTH = 2 * (0.5 + 0.75 + 0.875)


def lens_volume(radius, distance):
    """The volume two balls of `radius` share, their centres `distance` apart."""
    if distance >= 2 * radius:
        return 0.0
    return math.pi * (4 * radius + distance) * (2 * radius - distance) ** 2 / 12


def assert_vector(got, want, atol):
    assert isinstance(got, np.ndarray) and got.shape == (3,) and got.dtype == np.float64
    np.testing.assert_allclose(got, want, rtol=0, atol=atol)


def test_two_offset_cubes_share_the_box_of_their_intersection():
    found = delta.overlap(delta.box(), delta.box().translate(OFFSET))
    assert isinstance(found, delta.Overlap) and found
    assert found.volume == pytest.approx(CUBES_VOLUME, abs=1e-14)
    assert_vector(found.centroid, CUBES_CENTROID, 1e-14)
    assert_vector(found.area_vector, CUBES_AREA_VECTOR, 1e-14)
    assert_vector(found.area_vector_b, -np.array(CUBES_AREA_VECTOR), 1e-14)
    assert_vector(found.moment, found.total.moment, 0)
    assert found.curve_length == pytest.approx(CUBES_CURVE_LENGTH, abs=1e-13)
    assert found.touching == 0 and found.segments >= 6
    assert len(found.regions) == 1
    region = found.regions[0]
    assert isinstance(region, delta.OverlapRegion)
    assert region.volume == pytest.approx(CUBES_VOLUME, abs=1e-14)
    assert_vector(region.centroid, CUBES_CENTROID, 1e-14)
    assert region.curve_length == pytest.approx(CUBES_CURVE_LENGTH, abs=1e-13)
    assert 0 < region.triangles <= 24
    assert "OverlapRegion(volume=" in repr(region) and "Overlap(volume=" in repr(found)

    assert len(found.curves) == 1
    curve = found.curves[0]
    assert isinstance(curve, delta.IntersectionCurve)
    points = curve.points
    assert points.dtype == np.float64 and points.ndim == 2 and points.shape[1] == 3
    assert curve.closed and np.array_equal(points[0], points[-1])
    assert len(curve) == len(points) - 1 == found.segments
    for ids in (curve.triangles_a, curve.triangles_b):
        assert ids.dtype == np.uint32 and ids.shape == (len(points) - 1,)
        assert (ids < 12).all()
    assert curve.region == 0
    assert curve.length == pytest.approx(CUBES_CURVE_LENGTH, abs=1e-13)
    np.testing.assert_allclose(
        np.linalg.norm(np.diff(points, axis=0), axis=1).sum(), curve.length, rtol=1e-14
    )
    # Every point lies on an edge of the shared box where a face of A meets a face of B.
    on_a = np.isclose(points, 0.5, rtol=0, atol=1e-12).any(axis=1)
    on_b = np.isclose(points, [0.0, -0.25, -0.375], rtol=0, atol=1e-12).any(axis=1)
    assert on_a.all() and on_b.all()


def test_query_meshes_at_their_poses_and_plain_meshes_agree():
    a, b = delta.box(), delta.box()
    moved = delta.QueryMesh(b).transform(delta.RigidTransform(delta.Quaternion(), OFFSET))
    with_pose = delta.overlap(delta.QueryMesh(a), moved)
    plain = delta.overlap(a, b.translate(OFFSET))
    assert with_pose.volume == pytest.approx(plain.volume, abs=1e-14)
    assert_vector(with_pose.centroid, plain.centroid, 1e-14)
    # A turn of B about its own centre by 90° about z leaves the cube as it was.
    turned = delta.QueryMesh(delta.box()).transform(
        delta.RigidTransform(delta.Quaternion.from_axis_angle((0, 0, 1), math.pi / 2), OFFSET)
    )
    assert delta.overlap(a, turned).volume == pytest.approx(CUBES_VOLUME, abs=1e-12)


def test_swapping_the_meshes_swaps_the_surface_integrals():
    a, b = delta.box(), delta.box().translate(OFFSET)
    ab, ba = delta.overlap(a, b), delta.overlap(b, a)
    assert ba.volume == pytest.approx(ab.volume, abs=1e-14)
    assert_vector(ba.centroid, ab.centroid, 1e-14)
    assert_vector(ba.area_vector, ab.area_vector_b, 1e-14)
    assert_vector(ba.area_vector_b, ab.area_vector, 1e-14)


def test_without_curves_the_integrals_are_the_same():
    a, b = delta.box(), delta.box().translate(OFFSET)
    full, bare = delta.overlap(a, b), delta.overlap(a, b, curves=False)
    assert bare.curves == []
    assert bare.volume == full.volume and bare.segments == full.segments
    assert_vector(bare.area_vector, full.area_vector, 0)


def test_apart_and_nested_meshes():
    apart = delta.overlap(delta.box(), delta.icosphere(2).translate((3, 0, 0)))
    assert not apart and apart.volume == 0.0 and apart.regions == [] and apart.curves == []
    assert np.isfinite(apart.centroid).all()
    # A ball wholly inside a box: A ∩ B is the ball, and no surfaces cross.
    ball = delta.icosphere(2, 0.25)
    nested = delta.overlap(delta.box(), ball)
    assert nested.volume == pytest.approx(ball_volume(ball), rel=1e-12)
    assert nested.curves == [] and nested.segments == 0 and len(nested.regions) == 1


def ball_volume(mesh):
    """The volume a closed, outward-oriented mesh encloses (divergence theorem)."""
    v = np.asarray(mesh.vertices)[np.asarray(mesh.triangles)]
    return np.einsum("ij,ij->i", v[:, 0], np.cross(v[:, 1], v[:, 2])).sum() / 6


@pytest.mark.parametrize("distance", [0.3, 1.0, 1.7])
def test_two_icospheres_share_about_the_spherical_lens(distance):
    # The inscribed polyhedra share less than the balls: their surfaces lie inside the spheres by
    # a mean gap g, a third of the radius times the fraction the polyhedron's volume falls short.
    # So the shared volume falls short by about g times the lens's surface (two caps of height
    # R - d/2), and the circle where the spheres cross shrinks: its radius squared by about 2g.
    radius = 1.0
    exact = lens_volume(radius, distance)
    caps = 4 * math.pi * radius * (radius - distance / 2)
    disc_radius2 = radius**2 - (distance / 2) ** 2
    errors = []
    for level in (3, 4, 5):
        sphere = delta.icosphere(level, radius)
        found = delta.overlap(sphere, delta.icosphere(level, radius).translate((distance, 0, 0)))
        gap = radius / 3 * (1 - ball_volume(sphere) / (4 * math.pi / 3 * radius**3))
        assert len(found.regions) == 1 and len(found.curves) == 1 and found.curves[0].closed
        errors.append((exact - found.volume) / exact)
        expected = gap * caps / exact
        assert 0.5 * expected < errors[-1] < 1.5 * expected, (level, errors[-1], expected)
        # The centroid lies halfway between the centres, on the axis (the icosphere is mirror
        # symmetric in the coordinate planes).
        assert_vector(found.centroid, (distance / 2, 0, 0), 1e-12)
        # A's cap inside B has the area vector of the disc where the surfaces cross, along +x.
        disc = math.pi * (disc_radius2 - 2 * gap)
        assert_vector(found.area_vector, (disc, 0, 0), 2 * math.pi * gap)
        np.testing.assert_allclose(found.area_vector, -found.area_vector_b, atol=1e-12)
        circle = 2 * math.pi * math.sqrt(disc_radius2 - 2 * gap)
        assert found.curve_length == pytest.approx(circle, rel=2 * gap / disc_radius2)
        assert found.curve_length < 2 * math.pi * math.sqrt(disc_radius2)
    assert errors[0] > errors[1] > errors[2] > 0
    # A finer sphere halves the error about four times a level (the gap goes as the edge squared).
    assert errors[2] < errors[0] / 8


def test_the_volume_matches_a_monte_carlo_estimate_by_inside_tests(rng):
    # Independent of the overlap code: the fraction of random points inside both meshes, by
    # delta.distance's signs (exact off the surface), times the box sampled.
    a = delta.granulate(5)
    b = delta.granulate(6).translate((0.4, 0.1, -0.2))
    found = delta.overlap(a, b)
    assert found
    lower = np.maximum(a.bounds[0], b.bounds[0])
    upper = np.minimum(a.bounds[1], b.bounds[1])
    count = 200_000
    points = lower + (upper - lower) * rng.random((count, 3))
    inside = (
        delta.distance(a, points, signed=True)["inside"]
        & delta.distance(b, points, signed=True)["inside"]
    )
    box = np.prod(upper - lower)
    fraction = inside.mean()
    sigma = box * math.sqrt(fraction * (1 - fraction) / count)
    assert abs(found.volume - box * fraction) < 5 * sigma, (found.volume, box * fraction, sigma)
    centroid = points[inside].mean(axis=0)
    np.testing.assert_allclose(found.centroid, centroid, atol=0.02 * np.max(upper - lower))


def test_coplanar_faces_get_the_mean_of_both_sides():
    # Aligned cubes face to face: their side faces lie in one plane, where the volume has only
    # one-sided derivatives; one side alone pushes them sideways.
    a, b = delta.box((0.02, 0.02, 0.02)), delta.box((0.02, 0.02, 0.02), (0, 0, 0.019))
    found = delta.overlap(a, b)
    assert found.coplanar > 0 and not found.one_sided
    assert_vector(found.area_vector, (0, 0, 4e-4), 1e-19)
    one_side = delta.overlap(a, b, symmetric=False)
    assert one_side.one_sided and one_side.coplanar == found.coplanar
    assert_vector(one_side.area_vector, (2e-5, 2e-5, 4e-4), 1e-18)
    assert one_side.volume == found.volume
    with pytest.raises(TypeError):
        delta.overlap(a, b, symmetric=1)
    # Offset cubes meet in no plane: both answers are one.
    plain = delta.overlap(delta.box(), delta.box().translate(OFFSET))
    assert plain.coplanar == 0 and not plain.one_sided


def test_wrong_types_raise_type_error():
    box = delta.box()
    for a, b in ((box, "box"), (None, box), (np.zeros((3, 3)), box), (box, [box])):
        with pytest.raises(TypeError):
            delta.overlap(a, b)


def test_open_and_self_intersecting_meshes_are_refused():
    with pytest.raises(delta.Error) as error:
        delta.overlap(delta.quad(), delta.box())
    assert isinstance(error.value, ValueError)
    with pytest.raises(delta.Error):
        delta.overlap(delta.box(), delta.quad())
    # Two boxes in one mesh, crossing each other: closed and oriented, but self-intersecting.
    first, second = delta.box(), delta.box().translate((0.5, 0.5, 0.5))
    vertices = np.vstack([first.vertices, second.vertices])
    triangles = np.vstack([first.triangles, np.asarray(second.triangles) + len(first.vertices)])
    with pytest.raises(delta.Error):
        delta.overlap(delta.Mesh(vertices, triangles), delta.box().translate((3, 0, 0)))


def test_matches_the_command_line_tool(cli_json):
    answer = cli_json("overlap", "builtin:box", "builtin:box", "--translate-b", "0.5,0.25,0.125")
    found = delta.overlap(delta.box(), delta.box().translate(OFFSET))
    assert answer["volume"] == pytest.approx(found.volume, abs=1e-15)
    for key in ("centroid", "area_vector", "area_vector_b", "moment"):
        np.testing.assert_allclose(answer[key], getattr(found, key), rtol=0, atol=1e-15)
    assert answer["curve_length"] == pytest.approx(found.curve_length, abs=1e-15)
    assert answer["curves"] == len(found.curves) and answer["segments"] == found.segments
    assert answer["touching"] == found.touching
    assert answer["coplanar"] == found.coplanar and answer["one_sided"] == found.one_sided
    assert len(answer["regions"]) == 1
    region = answer["regions"][0]
    assert set(region) == {
        "volume", "centroid", "area_vector", "area_vector_b", "moment", "curve_length", "triangles"
    }
    assert region["triangles"] == found.regions[0].triangles
    for phase in ("load_s", "build_s", "query_s"):
        assert answer[phase] >= 0


def test_overlap_releases_the_gil():
    from test_gil import assert_ran_alongside

    a = delta.QueryMesh(delta.icosphere(6))  # 81920 triangles: about 0.1 s of overlap
    b = a.copy().transform(delta.RigidTransform.translation_by((0.5, 0.1, 0)))
    serial = delta.overlap(a, b)
    threaded = assert_ran_alongside(lambda: delta.overlap(a, b))
    assert threaded.volume == serial.volume and threaded.segments == serial.segments
    np.testing.assert_array_equal(threaded.curves[0].points, serial.curves[0].points)
