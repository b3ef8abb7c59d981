"""The guide's "Distance fields for immersed boundaries" (docs/guide.md) in Python: an adaptive grid
that follows a moving body with its signed distance at every vertex, written for ParaView; and the
batched query that a code with its own grid calls instead."""

import os
import sys

import numpy as np

import delta

# [guide:begin grid]
body = delta.QueryMesh(delta.icosphere(3, 0.3))  # closed: signed distances
grid = delta.ib.AdaptiveGrid(body, levels=6,  # the finest cells are 1/64 of the domain
                             domain=[(-1, -1, -1), (1, 1, 1)])  # fixed; the body moves inside it
for step in range(1, 6):
    moved = grid.move_boundary(delta.RigidTransform.translation_by((0.05, 0, 0)))
    print(f"step {step}: {grid.leaf_count} leaf cells, {grid.vertex_count} vertices, "
          f"{moved['queries']} queried again")
phi = grid.distances  # per vertex, negative inside: a read-only view, no copy
error = grid.error_bounds  # 0 within grid.exact_band
grid.write_vtu("grid.vtu")  # open it in ParaView
# [guide:end grid]

# Every distance is within its error bound of the exact one, and exact in the band.
exact = delta.signed_distance(delta.distance(grid.boundary, grid.positions, signed=True))
in_band = np.abs(phi) <= grid.exact_band
wrong = np.where(in_band, phi != exact, np.abs(phi - exact) > error)
wrong |= np.signbit(phi) != np.signbit(exact)
if wrong.any():
    v = np.flatnonzero(wrong)[0]
    sys.exit(f"vertex {v}: {phi[v]!r}, exact {exact[v]!r}, error bound {error[v]:g}")

# [guide:begin own-grid]
# A code with its own grid: the new vertices of a refinement step, answered in one batch.
# Within the band they get exact signed distances; beyond it, the triangle is NO_TRIANGLE.
band = 0.1
new_vertices = np.array([(-1.0 + 0.05 * i, 0.01, 0.02) for i in range(41)])
answers = np.empty(len(new_vertices), delta.distance_dtype)  # reused; filled once the batch is done
delta.distance(grid.boundary, new_vertices, eps=band, signed=True, out=answers)
found = answers["triangle"] != delta.NO_TRIANGLE
for x, d in zip(new_vertices[found, 0], delta.signed_distance(answers[found])):
    print(f"x = {x:+.2f}: {d:+.4f}")
# [guide:end own-grid]

if not ((phi < 0).any() and found.any() and os.path.getsize("grid.vtu") > 0):
    sys.exit("no vertex inside, no new vertex within the band, or an empty grid.vtu")
