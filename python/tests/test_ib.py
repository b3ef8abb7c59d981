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


def test_a_move_far_from_the_origin_gives_the_cells_of_a_new_grid():
    # Found by an audit: a domain at 1e6 of side 2^-10 and a face 40 ulp of 1e6 from its corner.
    # The bounds on the remembered distances allowed for rounding relative to the domain's size
    # only, while the poses' images round by ulps of 1e6: after two moves of 1e-8 rad the moved
    # grid kept its root unsplit (the corner's distance 43 ulp, bound 3.2 ulp, exact 38.9 ulp)
    # where a new grid at that pose splits it.
    origin, side = 1e6, 2.0**-10
    ulp = np.spacing(origin)
    domain = [(origin,) * 3, (origin + side,) * 3]
    face = origin - 40 * ulp
    lower, upper = [origin - side] * 3, [face, origin + 2 * side, origin + 2 * side]
    corners = np.array([[x, y, z] for z in (lower[2], upper[2]) for y in (lower[1], upper[1])
                        for x in (lower[0], upper[0])])
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    box = delta.QueryMesh(delta.Mesh(corners, np.array(
        [t for q in quads for t in ([q[0], q[1], q[2]], [q[0], q[2], q[3]])])))
    factor = 39.7 * ulp / delta.ib.AdaptiveGrid(box, levels=5, domain=domain).cell_diagonal(0)
    first = np.array([[0.9999999999999993, 2.1871083152538317e-08, 2.750654766092997e-08, -0.04937763046473265],
                      [-2.1871083158328786e-08, 0.9999999999999998, 2.1051219663196263e-10, 0.02166057121939957],
                      [-2.7506547656325836e-08, -2.105127982299538e-10, 0.9999999999999997, 0.02771706087514758],
                      [0, 0, 0, 1.0]])
    second = np.array([[1.0, 6.926188533749026e-10, -9.494904116189099e-10, 0.00025687168817967176],
                       [-6.92618852848149e-10, 1.0, 5.547750604922273e-10, 0.00013784365728497505],
                       [9.494904120031576e-10, -5.547750598345922e-10, 1.0, -0.0003947153454646468],
                       [0, 0, 0, 1.0]])
    moved = delta.ib.AdaptiveGrid(box, levels=5, domain=domain, refine_factor=factor, exact_band=0.0)
    moved.move_boundary_to(first)
    moved.move_boundary_to(second)
    placed = box.copy()
    placed.set_pose(second)
    fresh = delta.ib.AdaptiveGrid(placed, levels=5, domain=domain, refine_factor=factor,
                                  exact_band=0.0)
    assert list(moved.leaves_per_level) == list(fresh.leaves_per_level) == [0, 8, 0, 0, 0, 0]
    exact = delta.distance(placed, np.asarray(moved.positions))["distance"]
    assert (np.abs(np.abs(moved.distances) - exact) <= moved.error_bounds).all()
