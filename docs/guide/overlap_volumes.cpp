// The guide's "Overlap volumes and intersection curves" (docs/guide.md): two icospheres that
// overlap, the volume they share against the lens of the spheres, the intersection curve, and
// the force and torque of a volume-based contact law. Exits non-zero when a result is wrong.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "delta/delta.h"
#include "delta/query/overlap.h"

namespace {

/// The volume of an icosphere's polyhedron over that of its sphere, less than 1: the mesh is
/// inscribed, so every volume it bounds falls short by about this fraction.
double inscribedFraction(int level) {
  const delta::Mesh mesh = delta::primitives::icosphere(level);
  double volume = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const delta::TriangleIndices& corners = mesh.triangles()[t];
    const delta::Vec3 &p = mesh.vertices()[corners[0]], &q = mesh.vertices()[corners[1]],
                      &r = mesh.vertices()[corners[2]];
    volume += dot(p, cross(q, r)) / 6.0;
  }
  return volume / (4.0 * std::numbers::pi / 3.0);
}

}  // namespace

int main() try {
  // [guide:begin overlap]
  namespace cd = delta::contactdetection;
  const double radius = 1.0, d = 1.2;  // two unit spheres, centres 1.2 apart
  const delta::QueryMesh a(delta::primitives::icosphere(5, radius));  // 20480 triangles
  delta::QueryMesh b = a;  // shares the prepared data; its own pose
  b.transform(delta::RigidTransform::translationBy({d, 0, 0}));
  const cd::Overlap shared = cd::overlap(a, b);  // throws for open or self-crossing meshes

  const double lens =
      std::numbers::pi * (4 * radius + d) * (2 * radius - d) * (2 * radius - d) / 12;
  std::printf("A ∩ B: %.6f (the spheres' lens: %.6f), regions %zu\n", shared.total.volume, lens,
              shared.regions.size());
  for (const cd::IntersectionCurve& curve : shared.curves)
    std::printf("curve of %zu segments, closed %d, length %.6f\n", curve.trianglesA.size(),
                curve.closed, curve.length);

  // A contact law with energy w(V) = k V²/2: force on b = w'(V) areaVector, torque on b about
  // its centre c = w'(V) (moment + (centroid - c) × areaVector); a gets the opposites.
  const double k = 1e4, pressure = k * shared.total.volume;  // w'(V)
  const delta::Vec3 centreB{d, 0, 0};
  const delta::Vec3 force = pressure * shared.total.areaVector;
  const delta::Vec3 torque =
      pressure *
      (shared.total.moment + cross(shared.total.centroid - centreB, shared.total.areaVector));
  std::printf("force on b %.6g along x, torque on b %.1g (zero by symmetry)\n", force.x,
              length(torque));
  // [guide:end overlap]

  // The polyhedra share a little less than the spheres. Their surfaces lie inside the spheres by
  // a mean gap g, a third of the radius times the fraction their volume falls short (0.054% at
  // level 5), so the shared volume falls short by about g times the lens's surface, two caps of
  // height R - d/2 (0.10% here), and the circle where the surfaces cross has its radius squared
  // shrunk by about 2g.
  const double gap = radius * (1.0 - inscribedFraction(5)) / 3.0;
  const double caps = 4 * std::numbers::pi * radius * (radius - d / 2);
  const double expected = gap * caps / lens, error = (lens - shared.total.volume) / lens;
  const double discRadius2 = radius * radius - d * d / 4 - 2 * gap;
  const double disc = std::numbers::pi * discRadius2;
  const double circle = 2 * std::numbers::pi * std::sqrt(discRadius2);
  const bool right = shared.regions.size() == 1 && shared.curves.size() == 1 &&
                     shared.curves[0].closed && error > 0.5 * expected && error < 1.5 * expected &&
                     std::abs(shared.total.centroid.x - d / 2) < 1e-12 &&
                     std::abs(force.x / pressure - disc) < 2 * std::numbers::pi * gap &&
                     std::abs(shared.curves[0].length - circle) < 2 * gap / discRadius2 * circle &&
                     std::hypot(force.y, force.z) < 1e-9 * force.x &&
                     length(torque) < 1e-9 * length(force) * radius;  // mirror-symmetric: no torque
  if (!right) {
    std::fprintf(stderr, "overlap_volumes: unexpected result (volume error %g, expected %g)\n",
                 error, expected);
    return 1;
  }
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "overlap_volumes: %s\n", error.what());
  return 1;
}
