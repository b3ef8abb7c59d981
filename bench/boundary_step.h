#pragma once

// A time step's motion of an immersed boundary, for the benchmarks of ib::AdaptiveGrid
// (bench/ib_bench.cpp and W5 of bench/peers/peers_bench.cpp): the boundary turned about its box
// centre and moved, by a fixed small amount, as a body carried by a flow moves in one step.

#include <algorithm>
#include <cstddef>

#include "delta/core/rotation.h"
#include "delta/core/triangle.h"
#include "delta/core/vec3.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/query_mesh.h"

namespace delta::bench {

/// The largest displacement of a vertex of `boundary` (where it is now) under `motion`.
inline double largestVertexDisplacement(const QueryMesh& boundary, const RigidTransform& motion) {
  const TriangleSoA& triangles = boundary.triangles();
  double largest = 0.0;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Triangle triangle = triangles.triangle(t);
    for (const Vec3& vertex : {triangle.a, triangle.b, triangle.c}) {
      const Vec3 p = boundary.pose().apply(vertex);
      largest = std::max(largest, length(motion.apply(p) - p));
    }
  }
  return largest;
}

/// A step of `boundary` where it is now: turned about the centre of its box (axis (0.2, 0.3, 1))
/// and moved along (0.5, 0.3, 0.1), the turn's arc at half the box diagonal equal to the shift,
/// both scaled so that the vertex that moves furthest moves `distance` (one secant step on the
/// scale: within 10⁻⁵ relative for the fifth of a finest cell the benchmarks ask for, armadillo
/// and fandisk at levels 6 and 7). Compose it with the pose: AdaptiveGrid::moveBoundary(step), or
/// step * pose.
inline RigidTransform boundaryStep(const QueryMesh& boundary, double distance) {
  const Vec3 centre = boundary.pose().apply(boundary.bounds().center());
  const double radius = 0.5 * boundary.bounds().diagonal();
  const auto stepOf = [&](double shift) {
    return RigidTransform::translationBy(normalized(Vec3{0.5, 0.3, 0.1}) * shift) *
           RigidTransform::rotationAbout(Quaternion::fromAxisAngle({0.2, 0.3, 1.0}, shift / radius),
                                         centre);
  };
  const double trial = 0.5 * distance;
  return stepOf(trial * distance / largestVertexDisplacement(boundary, stepOf(trial)));
}

}  // namespace delta::bench
