#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"

namespace delta::detail {

/// The 30-bit Morton (Z-curve) code of `point` in `box`, 10 bits an axis (1024 cells; a point
/// outside the box takes the nearest cell).
std::uint64_t mortonCode(const Vec3& point, const Aabb& box) noexcept;

/// The 30-bit Morton code of cell (x, y, z) of a grid, each below 1024.
std::uint64_t mortonOfCell(std::uint32_t x, std::uint32_t y, std::uint32_t z) noexcept;

/// The indices in the low halves of `keys` (each a code of `codeBits` ≤ 32 bits, mortonCode's
/// 30 by default, above a 32-bit index), in ascending order of the codes, ties in index order.
/// Sorts `keys` (a radix sort: O(n) a digit of 10 bits).
std::vector<std::uint32_t> orderOfKeys(std::vector<std::uint64_t>& keys, int codeBits = 30);

/// The indices [0, count) in Morton (Z-curve) order of `pointAt(i)` within the points' bounding
/// box, 10 bits an axis; ties (repeated points) by index. Consecutive runs are spatially compact:
/// the queries walk their points in this order so that neighbours reuse the tree nodes and
/// triangles the previous ones brought into the cache. Non-finite coordinates are not allowed.
std::vector<std::uint32_t> mortonOrder(std::size_t count, Vec3 (*pointAt)(const void*, std::size_t),
                                       const void* context);

/// The same for a callable `pointAt(i)`.
template <typename PointAt>
std::vector<std::uint32_t> mortonOrder(std::size_t count, const PointAt& pointAt) {
  return mortonOrder(
      count,
      [](const void* context, std::size_t i) { return (*static_cast<const PointAt*>(context))(i); },
      &pointAt);
}

}  // namespace delta::detail
