"""delta.ib.AdaptiveGrid against the C++ tool (`delta ib`) and against delta.distance() at its
vertices, before and after the boundary moves."""

import numpy as np
import pytest

import delta


@pytest.fixture(scope="module")
def grid(fandisk):
    return delta.ib.AdaptiveGrid(fandisk, levels=5)


def test_grid_equals_the_cli(grid, meshes, cli_json):
    expected = cli_json("ib", meshes / "fandisk.off", "--levels", 5)
    assert grid.leaf_count == expected["cells"]
    assert grid.leaves_per_level.tolist() == expected["cells_per_level"]
    assert grid.vertex_count == expected["vertices"]
    assert grid.exact_band == expected["exact_band"]
    assert grid.statistics["queries"] == expected["build_queries"]


def test_grid_distances_are_those_of_distance(grid, fandisk):
    distances = grid.distances
    assert distances.dtype == np.float64 and distances.shape == (grid.vertex_count,)
    assert not distances.flags.writeable and np.shares_memory(distances, grid.distances)
    positions = grid.positions
    assert positions.shape == (grid.vertex_count, 3)
    direct = delta.distance(fandisk, positions, signed=True)
    np.testing.assert_array_equal(distances, delta.signed_distance(direct))
    np.testing.assert_array_equal(grid.error_bounds, 0.0)
    assert (distances < 0).any() and (distances > 0).any()


def test_cells_describe_the_octree(grid):
    for level, leaves in enumerate(grid.leaves_per_level):
        cells = grid.cells(level)
        assert cells.dtype == delta.ib.cell_dtype
        assert (cells["level"] == level).all()
        assert (cells["first_child"] == 0xFFFFFFFF).sum() == leaves
        assert (cells["corners"] < grid.vertex_count).all()


def test_a_moving_boundary(fandisk):
    grid = delta.ib.AdaptiveGrid(delta.QueryMesh(fandisk), levels=5)
    before = grid.distances
    kept = before.copy()
    motion = delta.RigidTransform(delta.Quaternion.from_axis_angle((0, 0, 1), 0.05), (0.02, 0, 0))
    statistics = grid.move_boundary(motion)
    assert statistics["queries"] > 0 and statistics == grid.statistics
    np.testing.assert_array_equal(before, kept)  # a view taken before keeps its distances
    after = grid.distances
    assert not np.array_equal(after, kept)
    exact = delta.signed_distance(delta.distance(grid.boundary, grid.positions, signed=True))
    bounds = grid.error_bounds
    band = np.abs(exact) <= grid.exact_band
    assert band.any() and (bounds[band] == 0).all()
    np.testing.assert_array_equal(after[bounds == 0], exact[bounds == 0])
    assert (np.abs(after - exact) <= bounds).all()
    np.testing.assert_array_equal(np.sign(after), np.sign(exact))
    # Moved back to where it started: the cells of a new grid.
    grid.move_boundary_to(delta.RigidTransform())
    fresh = delta.ib.AdaptiveGrid(fandisk, levels=5)
    assert grid.leaves_per_level.tolist() == fresh.leaves_per_level.tolist()


def test_unsigned_grid_of_an_open_boundary_and_vtu(tmp_path):
    quad = delta.quad()
    with pytest.raises(delta.Error, match="unsigned"):
        delta.ib.AdaptiveGrid(quad, levels=4)
    grid = delta.ib.AdaptiveGrid(quad, levels=4, signed=False, exact_band=float("inf"))
    assert (grid.distances >= 0).all() and grid.levels == 4
    np.testing.assert_allclose(grid.domain[1] - grid.domain[0], 1.2)
    path = tmp_path / "grid.vtu"
    grid.write_vtu(path)
    text = path.read_bytes()
    assert text.startswith(b"<?xml") and b'Name="distance"' in text
    with pytest.raises(delta.Error):
        delta.ib.AdaptiveGrid(quad, levels=0, signed=False)


def test_a_grid_that_cannot_fit_is_refused_before_it_is_made():
    # Issue 21: `delta ib --levels 12` on an 80-triangle granulate exhausted the memory; the
    # Python module shares the ib layer's check, level by level, before the cells are made.
    granulate = delta.granulate(1)
    with pytest.raises(delta.Error, match="32-bit indices hold"):
        delta.ib.AdaptiveGrid(granulate, levels=16)


def test_a_refused_move_leaves_the_grid_as_it_was():
    # A move beyond the coordinate range was found out half-way through: the grid was left
    # without cells, and the next move crashed the interpreter.
    grid = delta.ib.AdaptiveGrid(delta.icosphere(1), levels=3)
    leaves, distances = grid.leaf_count, grid.distances.copy()
    with pytest.raises(delta.Error, match="AdaptiveGrid"):
        grid.move_boundary(delta.RigidTransform(translation=(1e61, 0, 0)))
    assert grid.leaf_count == leaves
    assert np.array_equal(grid.distances, distances)
    grid.move_boundary_to(delta.RigidTransform())
    assert grid.leaf_count == leaves
