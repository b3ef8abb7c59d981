"""Immersed boundaries with Δ: an adaptive Cartesian grid around a (moving) boundary mesh, with
the boundary's distance at every grid vertex::

    import delta

    grid = delta.ib.AdaptiveGrid(delta.load("fandisk.off"), levels=6)
    grid.distances            # read-only view, negative inside
    grid.positions            # (n, 3)
    grid.move_boundary(delta.RigidTransform.translation_by((0.005, 0, 0)))
    grid.write_vtu("grid.vtu")

As `delta ib MESH` on the command line.
"""

from ._delta import ib as _ib

AdaptiveGrid = _ib.AdaptiveGrid
cell_dtype = _ib.cell_dtype

__all__ = ["AdaptiveGrid", "cell_dtype"]
