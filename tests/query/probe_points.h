#pragma once

// Query points the point-query tests share: uniform in a grown box, and on and next to a mesh's
// vertices, edges and faces, from a seeded generator (the same points on every platform).

#include <cstdint>
#include <random>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta::test {

/// Uniform in [0, 1) from the generator's raw bits (the same on every platform).
inline double unit(std::mt19937_64& random) {
  return static_cast<double>(random() >> 11) * 0x1p-53;
}

/// `count` points uniform in `box` grown by `growth` of its extent on every side.
inline std::vector<Vec3> uniformAround(const Aabb& box, std::size_t count, double growth,
                                       std::mt19937_64& random) {
  const Vec3 lower = box.lower - box.extent() * growth, size = box.extent() * (1.0 + 2.0 * growth);
  std::vector<Vec3> points(count);
  for (Vec3& p : points)
    p = lower + Vec3{size.x * unit(random), size.y * unit(random), size.z * unit(random)};
  return points;
}

/// `count` points uniform in the mesh's box grown by 10% per side, then points near the surface
/// (for count / 4 random triangles: a vertex, an edge midpoint and the centroid, each exactly on
/// the triangle and nudged by ±1e-6 of the diagonal along its normal), a far point and the box's
/// centre.
inline std::vector<Vec3> probes(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const Aabb box = mesh.bounds();
  std::vector<Vec3> points = uniformAround(box, count, 0.1, random);
  const double nudge = 1e-6 * box.diagonal();
  for (std::size_t i = 0; i < count / 4; ++i) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    const Vec3 normal = normalized(t.areaVector());
    for (const Vec3& on : {t.a, (t.a + t.b) * 0.5, t.centroid()})
      for (double side : {-1.0, 0.0, 1.0})
        points.push_back(on + normal * (side * nudge));
  }
  points.push_back(box.center() + Vec3{1e3, -2e3, 5e2} * box.diagonal());
  points.push_back(box.center());
  return points;
}

}  // namespace delta::test
