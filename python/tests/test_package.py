"""The package as users meet it: where it was imported from, its type stubs and signatures,
pickling (for multiprocessing), 4×4 matrices as transforms, and .vtp output."""

import inspect
import multiprocessing
import os
import pathlib
import pickle
import subprocess
import sys

import numpy as np
import pytest

import delta

PACKAGE = pathlib.Path(delta.__file__).parent
ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_the_module_under_test_is_the_one_expected():
    # scripts/test_packages.sh runs this suite in a virtual environment with the wheel installed
    # and says where the module must come from (not the build tree a .pth file points at).
    expected = os.environ.get("DELTA_EXPECT_MODULE")
    if expected:
        assert str(PACKAGE).startswith(expected), (PACKAGE, expected)
    assert delta.__version__.count(".") == 2


def test_type_stubs_ship_with_the_package():
    for name in ("__init__.pyi", "dem.pyi", "ib.pyi", "py.typed"):
        assert (PACKAGE / name).is_file(), name
    stub = (PACKAGE / "__init__.pyi").read_text(encoding="utf-8")
    for name in ("class Mesh", "class QueryMesh", "def distance(", "def contacts(", "def load("):
        assert name in stub


def test_the_committed_stubs_are_those_of_the_built_module(tmp_path):
    # Regenerated from the module under test: a binding changed without `scripts/make_stubs.py`
    # fails here.
    script = ROOT / "scripts" / "make_stubs.py"
    if not script.is_file():
        pytest.skip("no source tree beside the tests")
    env = dict(os.environ, PYTHONPATH=str(PACKAGE.parent))
    subprocess.run([sys.executable, str(script), str(tmp_path)], check=True, env=env,
                   capture_output=True)
    for name in ("__init__.pyi", "dem.pyi", "ib.pyi"):
        committed = (ROOT / "python" / "delta" / name).read_text(encoding="utf-8")
        assert (tmp_path / name).read_text(encoding="utf-8") == committed, (
            f"python/delta/{name} is out of date: run PYTHONPATH=build/python /usr/bin/python3 "
            "scripts/make_stubs.py")


@pytest.mark.parametrize("name", ["distance", "contacts", "point_contacts", "load", "save",
                                  "granulate", "minimum_distance", "filter"])
def test_inspect_signature_sees_the_parameters_of_functions(name):
    parameters = inspect.signature(getattr(delta, name)).parameters
    assert parameters and "args" not in parameters


def test_inspect_signature_sees_methods_classes_and_submodules():
    assert list(inspect.signature(delta.distance).parameters)[:2] == ["mesh", "points"]
    assert list(inspect.signature(delta.Mesh).parameters) == ["vertices", "triangles"]
    assert list(inspect.signature(delta.QueryMesh.transform).parameters) == ["self", "motion"]
    assert "offset" in inspect.signature(delta.RigidTransform.translation_by).parameters
    assert "steps" in inspect.signature(delta.dem.World.run).parameters
    assert "levels" in inspect.signature(delta.ib.AdaptiveGrid).parameters
    # The wrappers are transparent: same answers, same errors.
    with pytest.raises(delta.Error):
        delta.distance(delta.granulate(1), np.zeros((2, 2)))


def moved_query_mesh():
    mesh = delta.QueryMesh(delta.granulate(5))
    mesh.transform(delta.RigidTransform(delta.Quaternion.from_axis_angle((1, 2, 3), 0.7),
                                        (0.3, -1.1, 2.0)))
    return mesh


def test_a_query_mesh_pickles_bit_for_bit():
    mesh = moved_query_mesh()
    again = pickle.loads(pickle.dumps(mesh))
    assert again.moved and again.triangle_count == mesh.triangle_count
    assert again.pose.matrix.tobytes() == mesh.pose.matrix.tobytes()
    points = np.random.default_rng(1).uniform(-3, 3, (2000, 3)) + (0.3, -1.1, 2.0)
    np.testing.assert_array_equal(delta.distance(again, points, signed=True),
                                  delta.distance(mesh, points, signed=True))
    unmoved = pickle.loads(pickle.dumps(delta.QueryMesh(delta.granulate(5))))
    assert not unmoved.moved


def test_query_meshes_at_many_poses_pickle_bit_for_bit():
    # Unpickling normalised the (unit) rotation again, which changes its last bits in some 2.5%
    # of poses: an audit found contacts 1.1e-10 apart at 1e6.
    rng = np.random.default_rng(0)
    base = delta.QueryMesh(delta.granulate(3))
    for k in range(200):
        mesh = base.copy()
        mesh.transform(delta.RigidTransform(delta.Quaternion(*rng.uniform(-1, 1, 4)),
                                            rng.uniform(-0.5, 0.5, 3) + (1e6, 0, 0)))
        again = pickle.loads(pickle.dumps(mesh))
        q, r = mesh.pose.rotation, again.pose.rotation
        assert (q.w, q.x, q.y, q.z) == (r.w, r.x, r.y, r.z), k


def test_a_mesh_pickles_bit_for_bit():
    mesh = delta.granulate(6).rotate((0, 0, 1), 0.3)
    again = pickle.loads(pickle.dumps(mesh))
    assert again.vertices.tobytes() == mesh.vertices.tobytes()
    assert again.triangles.tobytes() == mesh.triangles.tobytes()


def a_worker_distance(arguments):
    mesh, points = arguments
    return delta.distance(mesh, points, signed=True)["distance"]


def test_query_meshes_go_to_multiprocessing_workers():
    mesh = moved_query_mesh()
    batches = [np.random.default_rng(seed).uniform(-2, 2, (100, 3)) for seed in range(4)]
    with multiprocessing.get_context("spawn").Pool(2) as pool:
        answers = pool.map(a_worker_distance, [(mesh, batch) for batch in batches])
    for batch, answer in zip(batches, answers):
        np.testing.assert_array_equal(answer, delta.distance(mesh, batch, signed=True)["distance"])


def test_a_bad_pickled_state_is_an_error():
    with pytest.raises(delta.Error, match="pickled state"):
        delta.QueryMesh.__new__(delta.QueryMesh).__setstate__((1, 2))


def homogeneous(rotation, translation):
    matrix = np.eye(4)
    matrix[:3, :3] = rotation.matrix
    matrix[:3, 3] = translation
    return matrix


def test_a_4x4_matrix_is_taken_wherever_a_transform_is():
    rotation = delta.Quaternion.from_axis_angle((0, 1, 1), 0.4)
    motion = delta.RigidTransform(rotation, (1, 2, 3))
    matrix = homogeneous(rotation, (1, 2, 3))

    by_object, by_matrix = delta.QueryMesh(delta.granulate(2)), delta.QueryMesh(delta.granulate(2))
    by_object.transform(motion)
    by_matrix.transform(matrix)
    np.testing.assert_allclose(by_matrix.pose.matrix, by_object.pose.matrix, atol=1e-15)
    by_matrix.set_pose(matrix.tolist())  # nested lists too
    np.testing.assert_allclose(by_matrix.pose.matrix, motion.matrix, atol=1e-15)

    mesh_object, mesh_matrix = delta.granulate(2), delta.granulate(2)
    mesh_object.transform(motion)
    mesh_matrix.transform(matrix)
    np.testing.assert_allclose(mesh_matrix.vertices, mesh_object.vertices, atol=1e-14)

    grid = delta.ib.AdaptiveGrid(delta.icosphere(2), levels=3)
    grid.move_boundary(homogeneous(delta.Quaternion(), (0.01, 0, 0)))
    grid.move_boundary_to(np.eye(4))


@pytest.mark.parametrize("matrix, error, message", [
    (np.diag([2.0, 2, 2, 1]), delta.Error, "not a rotation"),            # a scale
    (np.diag([-1.0, 1, 1, 1]), delta.Error, "not a rotation"),           # a reflection
    (np.eye(3), delta.Error, r"shape \(4, 4\)"),
    (np.vstack([np.eye(4)[:3], [0, 0, 1, 1]]), delta.Error, "last row"),
    (np.full((4, 4), np.nan), delta.Error, "finite"),
    (np.eye(4, dtype=bool), TypeError, ""),
])
def test_a_bad_4x4_matrix_is_a_clear_error(matrix, error, message):
    for call in (delta.QueryMesh(delta.granulate(2)).transform,
                 delta.QueryMesh(delta.granulate(2)).set_pose, delta.granulate(2).transform):
        with pytest.raises(error, match=message):
            call(matrix)


def test_save_writes_vtk_polydata_in_double(tmp_path):
    mesh = delta.granulate(4).translate((0.1, 1e-9, 3.0000000000000004))
    path = tmp_path / "particle.vtp"
    delta.save(mesh, path)
    head = path.read_bytes().split(b"<AppendedData")[0].decode()  # the XML before the binary
    assert 'type="PolyData"' in head
    assert f'NumberOfPoints="{mesh.vertex_count}"' in head
    assert f'NumberOfPolys="{mesh.triangle_count}"' in head
    with pytest.raises(delta.Error, match=r"\.vtp"):
        delta.save(mesh, tmp_path / "particle.xyz")


def test_save_vtp_reads_back_in_vtk_bit_for_bit(tmp_path):
    vtk = pytest.importorskip("vtkmodules.vtkIOXML")
    from vtkmodules.util.numpy_support import vtk_to_numpy

    mesh = delta.granulate(4).translate((0.1, 1e-9, 3.0000000000000004))
    path = tmp_path / "particle.vtp"
    delta.save(mesh, path)
    reader = vtk.vtkXMLPolyDataReader()
    reader.SetFileName(str(path))
    reader.Update()
    data = reader.GetOutput()
    points = vtk_to_numpy(data.GetPoints().GetData())
    assert points.dtype == np.float64
    assert points.tobytes() == mesh.vertices.tobytes()
    assert data.GetNumberOfCells() == mesh.triangle_count
