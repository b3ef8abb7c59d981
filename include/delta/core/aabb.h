#pragma once

#include <limits>

#include "delta/core/vec3.h"

namespace delta {

/// An axis-aligned bounding box. Default-constructed it is empty (lower > upper), and extending
/// an empty box by a point gives the point's box.
///
/// Threading: a value type; no shared state.
struct Aabb {
  Vec3 lower{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
  Vec3 upper{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity()};

  constexpr bool empty() const noexcept {
    return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z;
  }
  constexpr void extend(const Vec3& p) noexcept {
    lower = min(lower, p);
    upper = max(upper, p);
  }
  constexpr void extend(const Aabb& box) noexcept {
    lower = min(lower, box.lower);
    upper = max(upper, box.upper);
  }
  constexpr Vec3 center() const noexcept { return (lower + upper) * 0.5; }
  constexpr Vec3 extent() const noexcept { return upper - lower; }
  double diagonal() const noexcept { return empty() ? 0.0 : length(upper - lower); }
  constexpr bool contains(const Vec3& p) const noexcept {
    return p.x >= lower.x && p.x <= upper.x && p.y >= lower.y && p.y <= upper.y && p.z >= lower.z &&
           p.z <= upper.z;
  }
};

}  // namespace delta
