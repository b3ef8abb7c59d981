#pragma once

#include "delta/core/vec3.h"

namespace delta {

/// A ball: every point within `radius` of `center`.
///
/// Threading: a value type; no shared state.
struct Sphere {
  Vec3 center;
  double radius = 0.0;

  bool contains(const Vec3& p) const noexcept { return distance(p, center) <= radius; }
};

}  // namespace delta
