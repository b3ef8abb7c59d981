#pragma once

#include <algorithm>
#include <cstddef>
#include <limits>

#include "delta/core/vec3.h"

namespace delta {

/// An axis-aligned bounding box, closed (its faces belong to it). Default-constructed it is empty
/// (lower = +∞, upper = −∞), and extending an empty box by a point gives the point's box; a box
/// of one point (lower = upper) is not empty. Coordinates are expected to be finite (a NaN
/// extends nothing predictably).
///
/// Threading: a value type; no shared state.
struct Aabb {
  Vec3 lower{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
             std::numeric_limits<double>::infinity()};
  Vec3 upper{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
             -std::numeric_limits<double>::infinity()};

  /// Whether the box holds no point: lower > upper on some axis.
  constexpr bool empty() const noexcept {
    return lower.x > upper.x || lower.y > upper.y || lower.z > upper.z;
  }
  /// Grows the box to hold `p`.
  constexpr void extend(const Vec3& p) noexcept {
    lower = min(lower, p);
    upper = max(upper, p);
  }
  /// Grows the box to hold `box`; an empty box adds nothing.
  constexpr void extend(const Aabb& box) noexcept {
    lower = min(lower, box.lower);
    upper = max(upper, box.upper);
  }
  /// Corner `k` (0–7): upper along x where bit 0 of k is set, along y bit 1, along z bit 2.
  constexpr Vec3 corner(int k) const noexcept {
    return {k & 1 ? upper.x : lower.x, k & 2 ? upper.y : lower.y, k & 4 ? upper.z : lower.z};
  }
  /// The centre; NaN for an empty box.
  constexpr Vec3 center() const noexcept { return (lower + upper) * 0.5; }
  /// upper − lower per axis: 0 for a flat axis, −∞ for an empty box.
  constexpr Vec3 extent() const noexcept { return upper - lower; }
  /// The length of the diagonal; 0 for an empty box and for a box of one point.
  double diagonal() const noexcept { return empty() ? 0.0 : length(upper - lower); }
  /// Whether `p` lies in the box, faces included; false for an empty box and for NaN.
  constexpr bool contains(const Vec3& p) const noexcept {
    return p.x >= lower.x && p.x <= upper.x && p.y >= lower.y && p.y <= upper.y && p.z >= lower.z &&
           p.z <= upper.z;
  }
  /// The box grown by `margin` on every side (a negative margin shrinks it, possibly to an
  /// empty box); an empty box stays empty.
  constexpr Aabb grown(double margin) const noexcept {
    return {lower - Vec3{margin, margin, margin}, upper + Vec3{margin, margin, margin}};
  }
};

/// The squared distance from a point to a box: 0 inside and on the faces, +∞ for an empty box.
/// Without branches: the hot loop of several searches (a branch per axis was a coin toss to the
/// predictor).
///
/// Threading: a pure function.
[[gnu::always_inline]] constexpr double distanceSquared(const Vec3& p, const Aabb& box) noexcept {
  const double x = std::max(0.0, std::max(box.lower.x - p.x, p.x - box.upper.x));
  const double y = std::max(0.0, std::max(box.lower.y - p.y, p.y - box.upper.y));
  const double z = std::max(0.0, std::max(box.lower.z - p.z, p.z - box.upper.z));
  return x * x + y * y + z * z;
}

/// The squared distance between two boxes (0 where they overlap or touch): a lower bound of the
/// squared distance between any point of one and any point of the other; +∞ when either is empty.
///
/// Threading: a pure function.
constexpr double distanceSquared(const Aabb& a, const Aabb& b) noexcept {
  double sum = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double below = a.lower[axis] - b.upper[axis], above = b.lower[axis] - a.upper[axis];
    const double gap = below > above ? (below > 0.0 ? below : 0.0) : (above > 0.0 ? above : 0.0);
    sum += gap * gap;
  }
  return sum;
}

/// Whether two boxes are at least `gap` apart along some axis (then every pair of their points
/// is at least `gap` apart): the cheapest prune, one comparison per axis and side. Touching boxes
/// are apart by a gap of 0; an empty box is apart from everything (for a finite gap).
///
/// Threading: a pure function.
constexpr bool apart(const Aabb& a, const Aabb& b, double gap) noexcept {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (a.lower[axis] - b.upper[axis] >= gap || b.lower[axis] - a.upper[axis] >= gap) return true;
  return false;
}

/// The lowest axis (0, 1, 2: x, y, z) of the box's longest extent.
///
/// Threading: a pure function.
constexpr int longestAxis(const Aabb& box) noexcept {
  const Vec3 extent = box.extent();
  int axis = 0;
  for (int other = 1; other < 3; ++other)
    if (extent[static_cast<std::size_t>(other)] > extent[static_cast<std::size_t>(axis)])
      axis = other;
  return axis;
}

/// The box both boxes hold (empty where they do not meet; a shared face or corner is a flat box).
///
/// Threading: a pure function.
constexpr Aabb intersection(const Aabb& a, const Aabb& b) noexcept {
  return {max(a.lower, b.lower), min(a.upper, b.upper)};
}

}  // namespace delta
