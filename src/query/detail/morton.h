#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
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
/// Overwrites `keys` (a radix sort: O(n) a digit of at most 10 bits).
std::vector<std::uint32_t> orderOfKeys(std::vector<std::uint64_t>& keys, int codeBits = 30);

/// orderOfKeys into the caller's buffers, which a batch keeps from one call to the next:
/// order[k] is the index of the k-th key in that order and, where `codes` is not empty, codes[k]
/// its code. `keys` and `buffer` (of the same size) are overwritten; `order` and `codes` have
/// their size. Digits of at most 10 bits, as few as `codeBits` (0 < codeBits ≤ 32) needs.
void sortKeys(std::span<std::uint64_t> keys, std::span<std::uint64_t> buffer, int codeBits,
              std::span<std::uint32_t> order, std::span<std::uint32_t> codes);

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
