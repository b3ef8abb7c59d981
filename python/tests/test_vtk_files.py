"""The VTK files the `delta` tool writes (compressed VTK XML: io/vtk.h), opened by VTK's own readers
(Debian's python3-vtk9; skipped where it is not installed) and checked against what Δ computed:
counts, array names, types (integer ids and flags, Float64 values) and values."""

import pathlib
import xml.etree.ElementTree as ElementTree

import numpy as np
import pytest

import delta

from conftest import read_csv, write_xyz

vtk_io = pytest.importorskip("vtkmodules.vtkIOXML", reason="VTK's Python module (python3-vtk9)")
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402
from vtkmodules.vtkCommonCore import (  # noqa: E402
    vtkTypeFloat64Array,
    vtkTypeInt64Array,
    vtkTypeUInt8Array,
    vtkTypeUInt32Array,
)

FLOAT64 = vtkTypeFloat64Array().GetDataType()
INT64 = vtkTypeInt64Array().GetDataType()
UINT32 = vtkTypeUInt32Array().GetDataType()
UINT8 = vtkTypeUInt8Array().GetDataType()
VTK_VOXEL = 11


def read(path):
    """The data set in a .vtp, .vtu or .pvtp file, read by VTK; any error or warning VTK reports
    while reading fails the test."""
    path = pathlib.Path(path)
    reader = {
        ".vtp": vtk_io.vtkXMLPolyDataReader,
        ".vtu": vtk_io.vtkXMLUnstructuredGridReader,
        ".pvtp": vtk_io.vtkXMLPPolyDataReader,
    }[path.suffix]()
    problems = []
    for event in ("ErrorEvent", "WarningEvent"):
        reader.AddObserver(event, lambda caller, name: problems.append(name))
    reader.SetFileName(str(path))
    reader.Update()
    assert not problems, f"VTK reading {path}: {problems}"
    return reader.GetOutput()


def series(pvd):
    """The (time, file) entries of a ParaView collection, every file existing."""
    root = ElementTree.parse(pvd).getroot()
    assert root.get("type") == "Collection"
    entries = [
        (float(d.get("timestep")), pvd.parent / d.get("file")) for d in root.iter("DataSet")
    ]
    for _, file in entries:
        assert file.is_file(), file
    return entries


def array(data, name, data_type, components, where="point"):
    """The named point or cell array as NumPy, checked for its VTK type and components."""
    arrays = data.GetPointData() if where == "point" else data.GetCellData()
    found = arrays.GetArray(name)
    assert found is not None, f"no {where} array {name!r}"
    assert found.GetDataType() == data_type, (name, found.GetDataTypeAsString())
    assert found.GetNumberOfComponents() == components, name
    values = vtk_to_numpy(found)
    return values.reshape(-1, components) if components > 1 else values


def points(data):
    """The points of a data set as an (n, 3) array."""
    if data.GetNumberOfPoints() == 0:
        return np.zeros((0, 3))
    return vtk_to_numpy(data.GetPoints().GetData())


def rotated(quaternion, vectors):
    """Vectors turned by the unit quaternion (w, x, y, z)."""
    w, axis = quaternion[0], np.asarray(quaternion[1:])
    t = 2.0 * np.cross(axis, vectors)
    return vectors + w * t + np.cross(axis, t)


def test_dem_frames_open_and_glyphs_rebuild_the_particles(cli, tmp_path):
    out = tmp_path / "dem"
    cli("dem", "settle", "--particles", 8, "--steps", 600, "--output-every", 200, "--frames",
        "both", "--quiet", "--out", out)
    states = series(out / "particles_state.pvd")
    surfaces = series(out / "particles.pvd")
    assert [t for t, _ in states] == [t for t, _ in surfaces] and len(states) == 4
    shapes = {}
    for (_, state_file), (_, surface_file) in zip(states, surfaces):
        state = read(state_file)
        assert state.GetNumberOfPoints() == 8 and state.GetNumberOfVerts() == 8
        ids = array(state, "particle", UINT32, 1)
        assert sorted(ids.tolist()) == list(range(8))
        shape = array(state, "shape", UINT32, 1)
        velocity = array(state, "velocity", FLOAT64, 3)
        assert np.isfinite(velocity).all()
        array(state, "angular_velocity", FLOAT64, 3)
        orientation = array(state, "orientation", FLOAT64, 4)
        np.testing.assert_allclose(np.linalg.norm(orientation, axis=1), 1.0, rtol=1e-12)
        radius = array(state, "bounding_radius", FLOAT64, 1)
        assert (radius > 0).all()

        surface = read(surface_file)
        particle = array(surface, "particle", UINT32, 1, where="cell")
        array(surface, "shape", UINT32, 1, where="cell")
        array(surface, "velocity", FLOAT64, 3)
        assert surface.GetNumberOfPolys() == 8 * 80
        # A glyph of shape_K.vtp turned by `orientation` and moved to the point is the particle's
        # surface where the triangle frame has it, vertex for vertex (the particles in order).
        corners = points(surface)
        start = 0
        for p in range(8):
            k = int(shape[p])
            if k not in shapes:
                shapes[k] = points(read(out / f"shape_{k}.vtp"))
            body = shapes[k]
            moved = rotated(orientation[p], body) + points(state)[p]
            np.testing.assert_allclose(
                corners[start : start + len(body)], moved, rtol=0, atol=1e-12 * radius[p]
            )
            start += len(body)
        assert start == len(corners)
        assert set(particle.tolist()) == set(range(8))

    obstacles = read(out / "obstacles.vtp")
    array(obstacles, "obstacle", UINT32, 1, where="cell")

    # Contacts: two particles that collide (with frames every 5 steps, some hold the contact).
    out = tmp_path / "two"
    cli("dem", "two-particles", "--output-every", 5, "--quiet", "--out", out)
    touching = 0
    for _, file in series(out / "contacts.pvd"):
        contacts = read(file)
        touching += contacts.GetNumberOfPoints()
        force = array(contacts, "force", FLOAT64, 3)
        assert np.isfinite(force).all()
        array(contacts, "depth", FLOAT64, 1)
        # The point law has no couple and no overlap volume.
        np.testing.assert_array_equal(array(contacts, "couple", FLOAT64, 3), 0.0)
        np.testing.assert_array_equal(array(contacts, "volume", FLOAT64, 1), 0.0)
        for flag in ("overlap", "converged", "with_obstacle"):
            assert set(array(contacts, flag, UINT8, 1).tolist()) <= {0, 1}
        assert not array(contacts, "with_obstacle", UINT8, 1).any()
        pairs = zip(array(contacts, "particle", UINT32, 1), array(contacts, "other", UINT32, 1))
        assert all({int(a), int(b)} == {0, 1} for a, b in pairs)
    assert touching > 0, "the particles collide"

    # The volume law: each contact is an overlap region, its volume positive, its couple finite.
    out = tmp_path / "two-volume"
    cli("dem", "two-particles", "--contact-model", "volume", "--output-every", 5, "--quiet",
        "--out", out)
    regions = 0
    for _, file in series(out / "contacts.pvd"):
        contacts = read(file)
        regions += contacts.GetNumberOfPoints()
        assert (array(contacts, "volume", FLOAT64, 1) > 0).all()
        assert np.isfinite(array(contacts, "couple", FLOAT64, 3)).all()
    assert regions > 0, "the particles collide"


def test_ib_grid_opens_with_the_distances_delta_computed(cli, cli_json, tmp_path):
    static = tmp_path / "static"
    summary = cli_json("ib", "builtin:icosphere:2", "--levels", 4, "--out", static)
    grid = read(static / "grid.vtu")
    assert grid.GetNumberOfCells() == summary["cells"]
    assert grid.GetNumberOfPoints() == summary["vertices"]
    types = vtk_to_numpy(grid.GetCellTypesArray())
    assert (types == VTK_VOXEL).all()
    levels = array(grid, "level", UINT8, 1, where="cell")
    assert np.bincount(levels, minlength=5).tolist() == summary["cells_per_level"]
    array(grid, "finest_level", UINT8, 1)
    np.testing.assert_array_equal(array(grid, "error_bound", FLOAT64, 1), 0.0)
    distances = array(grid, "signed_distance", FLOAT64, 1)
    # The same points through `delta distance`: the same exact distances.
    xyz = tmp_path / "vertices.xyz"
    write_xyz(points(grid), xyz)
    csv = tmp_path / "distances.csv"
    cli("distance", "builtin:icosphere:2", "--points", xyz, "--signed", "--out", csv, "--quiet")
    expected = np.array([float(row["distance"]) * (-1 if row["inside"] == "1" else 1)
                         for row in read_csv(csv)])
    np.testing.assert_allclose(distances, expected, rtol=1e-14, atol=0)
    boundary = read(static / "boundary.vtp")
    assert boundary.GetNumberOfPolys() == 320

    moving = tmp_path / "moving"
    cli("ib", "builtin:icosphere:2", "--levels", 4, "--steps", 2, "--rotate", "0,0,1,10",
        "--translate", "0.05,0,0", "--unsigned", "--compression", 1, "--quiet", "--out", moving)
    frames = series(moving / "grid.pvd")
    assert [t for t, _ in frames] == [0.0, 1.0, 2.0]
    for _, file in frames:
        grid = read(file)
        assert grid.GetNumberOfCells() > 0
        assert (array(grid, "distance", FLOAT64, 1) >= 0).all()
        assert (array(grid, "error_bound", FLOAT64, 1) >= 0).all()
    for _, file in series(moving / "boundary.pvd"):
        assert read(file).GetNumberOfPolys() == 320


def test_distance_and_contact_points_open_with_their_csv_values(cli, tmp_path):
    vtp, csv = tmp_path / "distances.vtp", tmp_path / "distances.csv"
    arguments = ("distance", "builtin:icosphere:2", "--points", "builtin:uniform:300:7", "--signed",
                 "--eps", 0.3, "--quiet", "--out")
    cli(*arguments, vtp)
    cli(*arguments, csv)
    rows = read_csv(csv)
    data = read(vtp)
    assert data.GetNumberOfPoints() == len(rows) == 300
    triangle = array(data, "triangle", INT64, 1)
    assert triangle.tolist() == [int(r["triangle"]) if r["triangle"] else -1 for r in rows]
    signed = array(data, "signed_distance", FLOAT64, 1)
    for value, row in zip(signed, rows):
        if row["distance"]:
            sign = -1 if row["inside"] == "1" else 1
            assert value == sign * float(row["distance"])
        else:
            assert np.isnan(value)

    vtp, csv = tmp_path / "contacts.vtp", tmp_path / "contacts.csv"
    arguments = ("contact", "builtin:icosphere:3", "builtin:icosphere:3", "--translate-b",
                 "1.95,0,0", "--eps", 0.05, "--out")
    cli(*arguments, vtp)
    cli(*arguments, csv)
    rows = read_csv(csv)
    data = read(vtp)
    assert data.GetNumberOfPoints() == len(rows) > 0
    assert array(data, "triangle_a", UINT32, 1).tolist() == [int(r["triangle_a"]) for r in rows]
    assert array(data, "triangle_b", UINT32, 1).tolist() == [int(r["triangle_b"]) for r in rows]
    assert array(data, "overlap", UINT8, 1).tolist() == [int(r["overlap"]) for r in rows]
    np.testing.assert_array_equal(array(data, "distance", FLOAT64, 1),
                                  [float(r["distance"]) for r in rows])
    np.testing.assert_array_equal(points(data), [[float(r[c]) for c in "xyz"] for r in rows])


def test_overlap_curves_open_as_the_polylines_delta_computed(cli, tmp_path):
    vtp = tmp_path / "curves.vtp"
    cli("overlap", "builtin:granulate:1", "builtin:granulate:2", "--translate-b", "0.3,0,0",
        "--quiet", "--out", vtp)
    found = delta.overlap(delta.granulate(1), delta.granulate(2).translate((0.3, 0, 0)))
    data = read(vtp)
    assert data.GetNumberOfLines() == data.GetNumberOfCells() == len(found.curves) > 0
    assert data.GetNumberOfVerts() == data.GetNumberOfPolys() == 0
    np.testing.assert_array_equal(array(data, "curve", UINT32, 1, where="cell"),
                                  range(len(found.curves)))
    regions = array(data, "region", UINT32, 1, where="cell")
    closed = array(data, "closed", UINT8, 1, where="cell")
    lengths = array(data, "length", FLOAT64, 1, where="cell")
    triangle_a = array(data, "triangle_a", UINT32, 1)
    triangle_b = array(data, "triangle_b", UINT32, 1)
    corners = points(data)
    for c, curve in enumerate(found.curves):
        assert regions[c] == curve.region and closed[c] == curve.closed
        assert lengths[c] == curve.length
        cell = data.GetCell(c)
        ids = [cell.GetPointId(k) for k in range(cell.GetNumberOfPoints())]
        # A closed curve's polyline ends at its first point, which is stored once.
        assert len(ids) == len(curve.points) and (ids[0] == ids[-1]) == curve.closed
        np.testing.assert_array_equal(corners[ids], curve.points)
        segments = ids[:-1]
        assert triangle_a[segments].tolist() == curve.triangles_a.tolist()
        assert triangle_b[segments].tolist() == curve.triangles_b.tolist()
