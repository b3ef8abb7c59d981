"""The guide's "Overlap volumes and intersection curves" (docs/guide.md) in Python: two icospheres
that overlap, the volume they share against the lens of the spheres, the intersection curve, and
the two spheres saved for ParaView (a.vtp, b.vtp in the working folder).

    python3 overlap_volumes.py
"""

# [guide:begin overlap]
import math
import numpy as np
import delta

radius, d = 1.0, 1.2  # two unit spheres, centres 1.2 apart
a = delta.QueryMesh(delta.icosphere(5, radius))  # 20480 triangles
b = a.copy().transform(delta.RigidTransform.translation_by((d, 0, 0)))
shared = delta.overlap(a, b)  # a delta.Overlap; delta.Error for open or self-crossing meshes
lens = math.pi * (4 * radius + d) * (2 * radius - d) ** 2 / 12
print(f"A ∩ B: {shared.volume:.6f} (the spheres' lens: {lens:.6f}), regions {len(shared.regions)}")
for curve in shared.curves:  # points (n, 3); triangles_a, triangles_b per segment
    print(f"curve of {len(curve)} segments, closed {curve.closed}, length {curve.length:.6f}")

# A contact law with energy w(V) = k V²/2: force on b = w'(V) area_vector, torque on b about its
# centre c = w'(V) (moment + (centroid - c) × area_vector); a gets the opposites.
pressure = 1e4 * shared.volume  # w'(V)
force = pressure * shared.area_vector
torque = pressure * (shared.moment + np.cross(shared.centroid - (d, 0, 0), shared.area_vector))
print(f"force on b {force[0]:.6g} along x, torque on b {np.linalg.norm(torque):.1g}")

delta.save(delta.icosphere(5, radius), "a.vtp")  # for ParaView, beside the curves that
delta.save(delta.icosphere(5, radius).translate((d, 0, 0)), "b.vtp")  # `delta overlap` writes
# [guide:end overlap]

# As the C++ example checks: the polyhedra's surfaces lie inside the spheres by a mean gap g, a
# third of the radius times the fraction their volume falls short, so the shared volume falls
# short by about g times the lens's surface (two caps of height R - d/2), and the circle where
# the surfaces cross has its radius squared shrunk by about 2g.
sphere = delta.icosphere(5, radius)
corners = sphere.vertices[sphere.triangles]
volume = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum() / 6
gap = radius * (1 - volume / (4 * math.pi / 3 * radius**3)) / 3
expected = gap * 4 * math.pi * radius * (radius - d / 2) / lens
error = (lens - shared.volume) / lens
disc_radius2 = radius**2 - d**2 / 4 - 2 * gap
checks = {
    "one region, one closed curve": len(shared.regions) == 1 and len(shared.curves) == 1
    and shared.curves[0].closed,
    "the volume's shortfall": 0.5 * expected < error < 1.5 * expected,
    "the centroid": abs(shared.centroid[0] - d / 2) < 1e-12,
    "the area vector": abs(force[0] / pressure - math.pi * disc_radius2) < 2 * math.pi * gap,
    "the curve's length": abs(shared.curve_length - 2 * math.pi * math.sqrt(disc_radius2))
    < 4 * math.pi * gap / math.sqrt(disc_radius2),
    "no torque, no sideways force": np.linalg.norm(torque) < 1e-9 * force[0]
    and np.hypot(force[1], force[2]) < 1e-9 * force[0],
}
wrong = [name for name, right in checks.items() if not right]
if wrong:
    raise SystemExit(f"overlap_volumes: unexpected {', '.join(wrong)} (volume error {error:g}, "
                     f"expected about {expected:g})")
