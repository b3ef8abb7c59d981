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
/// Threading: a value type; no shared state.
struct ContactPoint {
  Vec3 x;
  Vec3 normal;               ///< P − x: from x toward the first geometry, length distance / 2
  Vec3 direction;            ///< unit vector from the second geometry toward the first
  double distance = 0.0;     ///< |P − Q|
  bool overlap = false;      ///< the geometries interpenetrate here
  std::uint32_t first = 0;   ///< triangle (or point) id in the first geometry
  std::uint32_t second = 0;  ///< triangle id in the second geometry
};

}  // namespace delta
