#pragma once

#include "delta/core/vec3.h"

namespace delta {

/// A ball: every point within `radius` of `center` (a radius of 0 is the point itself). Queries
/// that take spheres check them (sphereContacts, nearbyPairs) and say which radii they accept.
///
/// Threading: a value type; no shared state.
struct Sphere {
  Vec3 center;
  double radius = 0.0;

  /// Whether `p` lies in the closed ball (on the surface included).
  bool contains(const Vec3& p) const noexcept { return distance(p, center) <= radius; }
};

}  // namespace delta
