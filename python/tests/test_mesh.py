"""delta.Mesh, transforms, primitives, load and save: against the C++ library's own answers
(`delta info`) and the promises of the docstrings (validation, read-only views)."""

import copy
import math
import pickle

import numpy as np
import pytest

import delta

TETRA_VERTICES = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
TETRA_TRIANGLES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def tetra():
    return delta.Mesh(TETRA_VERTICES, TETRA_TRIANGLES)


def test_mesh_holds_what_it_was_given():
    mesh = tetra()
    assert mesh.vertex_count == 4 and mesh.triangle_count == 4
    assert mesh.vertices.dtype == np.float64 and mesh.vertices.shape == (4, 3)
    assert mesh.triangles.dtype == np.uint32 and mesh.triangles.shape == (4, 3)
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
    np.testing.assert_array_equal(mesh.triangles, TETRA_TRIANGLES)
    np.testing.assert_array_equal(mesh.bounds, [[0, 0, 0], [1, 1, 1]])
    assert mesh.closed and mesh.consistently_oriented
    assert mesh.volume == pytest.approx(1 / 6)
    assert mesh.area == pytest.approx(1.5 + math.sqrt(3) / 2)
    assert mesh.topology()["edges"] == 6


def test_views_are_read_only_and_share_the_mesh_storage():
    mesh = tetra()
    vertices = mesh.vertices
    assert not vertices.flags.writeable and not mesh.triangles.flags.writeable
    with pytest.raises(ValueError):
        vertices[0, 0] = 5.0
    # Two views of one mesh are the same memory: no copy.
    assert np.shares_memory(vertices, mesh.vertices)
    assert np.shares_memory(mesh.triangles, mesh.triangles)


def test_a_view_outlives_its_mesh_and_keeps_its_coordinates_through_a_transform():
    mesh = tetra()
    before = mesh.vertices
    mesh.translate((1.0, 2.0, 3.0))
    np.testing.assert_array_equal(before, TETRA_VERTICES)  # the snapshot it was taken of
    np.testing.assert_array_equal(mesh.vertices, np.add(TETRA_VERTICES, [1.0, 2.0, 3.0]))
    triangles = mesh.triangles
    del mesh
    np.testing.assert_array_equal(triangles, TETRA_TRIANGLES)


def test_transforms_chain_and_agree_with_each_other():
    mesh = tetra()
    assert mesh.rotate((0, 0, 1), 0.5).translate((1, 0, 0)) is mesh
    by_angle = tetra().rotate((1, 2, 3), 0.7, pivot=(0.5, 0.5, 0.5)).vertices
    q = delta.Quaternion.from_axis_angle((1, 2, 3), 0.7)
    by_quaternion = tetra().rotate(q, pivot=(0.5, 0.5, 0.5)).vertices
    by_matrix = tetra().rotate(q.matrix, pivot=(0.5, 0.5, 0.5)).vertices
    np.testing.assert_array_equal(by_angle, by_quaternion)
    np.testing.assert_allclose(by_matrix, by_quaternion, atol=1e-15)
    motion = delta.RigidTransform.rotation_about(q, (0.5, 0.5, 0.5))
    np.testing.assert_allclose(tetra().transform(motion).vertices, by_quaternion, atol=1e-15)
    np.testing.assert_allclose(motion.apply(TETRA_VERTICES), by_quaternion, atol=1e-15)
    np.testing.assert_allclose((motion.inverse() * motion).matrix, np.eye(4), atol=1e-15)
    np.testing.assert_array_equal(
        tetra().scale(2.0, pivot=(1, 1, 1)).vertices, 1 + 2 * (np.array(TETRA_VERTICES) - 1)
    )
    np.testing.assert_array_equal(
        tetra().stretch((1, 2, 3)).vertices, np.array(TETRA_VERTICES) * [1, 2, 3]
    )


def test_copies_and_pickles_are_independent():
    mesh = tetra()
    for other in (mesh.copy(), copy.copy(mesh), copy.deepcopy(mesh), pickle.loads(pickle.dumps(mesh))):
        np.testing.assert_array_equal(other.vertices, mesh.vertices)
        np.testing.assert_array_equal(other.triangles, mesh.triangles)
        other.translate((1, 0, 0))
        np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)


def test_inputs_are_converted_when_needed():
    as_int32 = delta.Mesh(np.array(TETRA_VERTICES, dtype=np.int32), np.array(TETRA_TRIANGLES, dtype=np.uint8))
    fortran = delta.Mesh(np.asfortranarray(np.array(TETRA_VERTICES, dtype=np.float32)), TETRA_TRIANGLES)
    for mesh in (as_int32, fortran):
        np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)
        np.testing.assert_array_equal(mesh.triangles, TETRA_TRIANGLES)


@pytest.mark.parametrize(
    "vertices, triangles, message",
    [
        ([[0, 0, 0], [1, 0, 0], [0, np.nan, 0]], [[0, 1, 2]], "vertex 2"),
        ([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]], [[0, 1, 2]], "not finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 3]], "refers to vertex 3"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, -1]], "vertex -1"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.zeros((0, 3), dtype=int), "no triangles"),
        ([[0, 0], [1, 0], [0, 1]], [[0, 1, 2]], r"shape \(n, 3\)"),
        ([0, 0, 0, 1, 0, 0, 0, 1, 0], [[0, 1, 2]], r"shape \(n, 3\)"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2, 0]], r"shape \(m, 3\)"),
    ],
)
def test_bad_meshes_raise_delta_error(vertices, triangles, message):
    with pytest.raises(delta.Error, match=message):
        delta.Mesh(vertices, triangles)


@pytest.mark.parametrize(
    "vertices, triangles, message",
    [
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2.0]], "integers"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, True]], "integers, not booleans"),
        ([["a", "b", "c"]] * 3, [[0, 1, 2]], "real numbers"),
        (np.zeros((3, 3), dtype=complex), [[0, 1, 2]], "real numbers"),
        ([[0, 0, 0], [1, 0, 0], [0, True, 0]], [[0, 1, 2]], "not booleans"),
        ([[0, 0, 0], [1, 0], [0, 1, 0]], [[0, 1, 2]], r"ragged list \(rows of 3 and 2 items\)"),
        ([[0, 0, 0], 1, [0, 1, 0]], [[0, 1, 2]], "ragged list .sequences and numbers mixed"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], ([0, 1, 2], [0, 1]), "ragged tuple .rows of 3 and 2"),
    ],
)
def test_meshes_of_what_is_not_numbers_raise_type_error(vertices, triangles, message):
    with pytest.raises(TypeError, match=message):
        delta.Mesh(vertices, triangles)


def test_delta_error_is_a_value_error_and_transforms_keep_the_mesh_on_failure():
    assert issubclass(delta.Error, ValueError)
    mesh = tetra()
    with pytest.raises(delta.Error):
        mesh.scale(-1.0)
    with pytest.raises(delta.Error):
        mesh.rotate((0, 0, 0), 1.0)
    with pytest.raises(delta.Error):
        mesh.rotate(np.diag([1.0, 1.0, -1.0]))  # a reflection
    with pytest.raises(delta.Error):
        mesh.translate((np.nan, 0, 0))
    with pytest.raises(delta.Error):
        delta.Quaternion(0, 0, 0, 0)
    np.testing.assert_array_equal(mesh.vertices, TETRA_VERTICES)


def test_primitives():
    assert delta.icosphere(2).triangle_count == 320
    sphere = delta.icosphere(0, radius=2.0, center=(1, 1, 1))
    np.testing.assert_allclose(np.linalg.norm(sphere.vertices - 1.0, axis=1), 2.0)
    box = delta.box((1, 2, 3), center=(1, 1, 1))
    assert box.triangle_count == 12 and box.volume == pytest.approx(6.0)
    assert delta.cylinder(segments=8).triangle_count == 32
    quad = delta.quad(2.0, 3.0)
    assert quad.triangle_count == 2 and not quad.closed and quad.volume is None
    granulate = delta.granulate(7)
    assert granulate.triangle_count == 80 and granulate.closed
    np.testing.assert_array_equal(delta.granulate(7).vertices, granulate.vertices)  # seeded
    with pytest.raises(delta.Error):
        delta.icosphere(9)
    with pytest.raises(delta.Error):
        delta.cylinder(segments=2)


def test_mass_properties_and_measures():
    box = delta.box((1, 2, 3))
    mass = box.mass_properties(density=2.0)
    assert mass["volume"] == pytest.approx(6.0) and mass["mass"] == pytest.approx(12.0)
    np.testing.assert_allclose(mass["centroid"], 0, atol=1e-15)
    np.testing.assert_allclose(np.diag(mass["inertia"]), 12.0 / 12 * np.array([13, 10, 5]))
    lengths = box.edge_lengths()
    assert lengths["min"] == pytest.approx(1.0) and lengths["max"] == pytest.approx(math.sqrt(13))
    center, radius = box.bounding_sphere()
    assert radius == pytest.approx(math.sqrt(14) / 2, rel=1e-6)
    assert box.degenerate_triangle_count == 0


@pytest.mark.parametrize("extension", ["stl", "ply", "obj"])
def test_save_and_load_round_trip(tmp_path, extension):
    mesh = delta.granulate(11).rotate((1, 1, 0), 0.3)
    path = tmp_path / f"granulate.{extension}"
    delta.save(mesh, path)
    loaded = delta.load(str(path))
    assert loaded.triangle_count == mesh.triangle_count
    # The same triangles in the same order, coordinates rounded to single precision.
    original = mesh.vertices[mesh.triangles].astype(np.float32).astype(np.float64)
    corners = loaded.vertices[loaded.triangles]
    if extension == "obj":  # text with 9 significant digits, read exactly: they name the float
        corners = corners.astype(np.float32).astype(np.float64)
    np.testing.assert_array_equal(corners, original)
    again, statistics = delta.load_with_statistics(path)
    np.testing.assert_array_equal(again.vertices, loaded.vertices)
    assert statistics["points_skipped"] == 0 and statistics["meshes"] >= 1
    assert statistics["precision"] == "exact"


def test_load_reads_decimals_exactly_and_reports_precision(tmp_path, meshes):
    path = tmp_path / "tricky.dat"  # OFF by its content, whatever the extension
    path.write_text("OFF\n4 4 0\n0.1 0.2 0.30000000000000004\n1e6 1e6 1e6\n"
                    "1000000.001 1e6 1e6\n1e6 1000000.001 1e6\n"
                    "3 0 1 2\n3 1 2 3\n3 0 2 3\n3 0 3 1\n")
    mesh, statistics = delta.load_with_statistics(path)
    np.testing.assert_array_equal(
        mesh.vertices, [[0.1, 0.2, 0.30000000000000004], [1e6, 1e6, 1e6],
                        [1000000.001, 1e6, 1e6], [1e6, 1000000.001, 1e6]])
    assert statistics["precision"] == "exact"
    _, gltf = delta.load_with_statistics(
        meshes.parent / "assimp/glTF2/BoxTextured-glTF/BoxTextured.gltf")
    assert gltf["precision"] == "single"
    (tmp_path / "huge.off").write_text("OFF\n3 1 0\n0 0 0\n1e999 0 0\n0 1 0\n3 0 1 2\n")
    with pytest.raises(delta.Error, match="line 4.*1e999"):
        delta.load(tmp_path / "huge.off")


def test_load_and_save_errors_name_the_file(tmp_path):
    with pytest.raises(delta.Error, match="missing.off"):
        delta.load(tmp_path / "missing.off")
    broken = tmp_path / "broken.off"
    broken.write_text("OFF\n3 1 0\n0 0 0\n1 0 0\n")
    with pytest.raises(delta.Error, match="broken.off"):
        delta.load(broken)
    with pytest.raises(delta.Error, match="mesh.xyz"):
        delta.save(tetra(), tmp_path / "mesh.xyz")


def test_real_mesh_matches_delta_info(meshes, cli_json):
    path = meshes / "armadillo.off"
    mesh = delta.load(path)
    info = cli_json("info", path)
    assert mesh.triangle_count == info["triangles"] == 52000
    assert mesh.vertex_count == info["vertices"]
    assert mesh.area == info["area"]
    assert mesh.volume == info["volume"]
    assert mesh.closed == info["closed"]
    assert mesh.degenerate_triangle_count == info["degenerate_triangles"]
    np.testing.assert_array_equal(mesh.bounds, [info["bounds"]["lower"], info["bounds"]["upper"]])
    assert mesh.edge_lengths()["mean"] == info["mesh_size"]["mean_edge"]


def test_arrays_too_large_for_memory_are_refused_before_they_are_copied():
    # A broadcast view costs nothing, but its float64 copy would: it was OOM-killed.
    triangle = np.array([[0, 1, 2]])
    huge = np.broadcast_to(np.zeros(3), (10**10, 3))
    with pytest.raises(ValueError, match="memory"):
        delta.Mesh(huge, triangle)
    with pytest.raises(ValueError, match="memory"):
        delta.Mesh(delta.box().vertices, np.broadcast_to(np.array([0, 1, 2]), (10**10, 3)))
    with pytest.raises(ValueError, match="memory"):
        delta.distance(delta.box(), huge)


def test_a_composition_whose_translation_overflows_is_refused():
    # A RigidTransform never holds a translation that is not finite (the constructor refuses
    # one); composing or inverting finite motions could make one.
    far = delta.RigidTransform(translation=(1e308, 0, 0))
    with pytest.raises(ValueError, match="overflows"):
        far * far
    turned = delta.RigidTransform(delta.Quaternion.from_axis_angle((0, 0, 1), 1.0), (1e308, 1e308, 0))
    with pytest.raises(ValueError, match="overflows"):
        turned.inverse()
    assert np.array_equal((far * delta.RigidTransform()).translation, [1e308, 0, 0])
