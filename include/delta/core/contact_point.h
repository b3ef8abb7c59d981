#pragma once

#include <cstdint>

#include "delta/core/vec3.h"

namespace delta {

/// Where two geometries come closer than the contact distance: the seed's contact point.
///
/// P is the closest point on the first geometry, Q on the second. `x` lies midway between them,
/// `normal` = P − x points from x to the first geometry (so −normal points to the second) and
/// its length is half the gap, |P − Q| / 2. `direction` is the unit vector of the same sense,
/// defined also where the normal cannot give one: for touching or intersecting triangles
/// (P = Q, `normal` = 0) it is the contact direction derived from the triangles' faces.
///
/// Where the geometries overlap and the query can say by how much — a sphere sunk into a wall
/// (query/sphere_contacts.h) — P is the first geometry's deepest point beyond Q, so `normal`
/// points the other way (−direction · depth / 2) and `distance` is the depth; `direction` always
/// points from the second geometry toward the first. `first` is a triangle id, a point index
/// (points–mesh) or a sphere index (sphere–mesh); `second` a triangle id.
///
/// Threading: a value type; no shared state.
struct ContactPoint {
  Vec3 x;
  Vec3 normal;            ///< P − x: from x toward the first geometry, length distance / 2
  Vec3 direction;         ///< unit vector from the second geometry toward the first
  double distance = 0.0;  ///< |P − Q|
  bool overlap = false;   ///< the geometries interpenetrate here
  /// The solver certified this pair's answer: always true for the exact solvers (hybrid, brute
  /// force) and the sphere and point queries; for Solver::Penalty its Newton's flag (error bound
  /// within kernels::kPenaltyTolerance of the pair's size; see kernels/penalty.h): a pair not
  /// converged still has a feasible point pair, but its distance may be too large.
  bool converged = true;
  std::uint32_t first = 0;   ///< triangle, point or sphere id in the first geometry
  std::uint32_t second = 0;  ///< triangle id in the second geometry
};

}  // namespace delta
