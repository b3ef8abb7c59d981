#include "morton.h"

#include <algorithm>
#include <utility>

#include "delta/core/aabb.h"

namespace delta::detail {
namespace {

/// The 21 low bits of `x` spread to every third bit of a 63-bit Morton code.
std::uint64_t spreadBits(std::uint64_t x) noexcept {
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

std::vector<std::uint32_t> mortonOrder(std::size_t count, Vec3 (*pointAt)(const void*, std::size_t),
                                       const void* context) {
  Aabb box;
  for (std::size_t i = 0; i < count; ++i)
    box.extend(pointAt(context, i));
  constexpr double kCells = 2097151.0;  // 2²¹ − 1
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(count);
  for (std::size_t i = 0; i < count; ++i) {
    const Vec3 point = pointAt(context, i);
    std::uint64_t code = 0;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double extent = box.upper[axis] - box.lower[axis];
      double unit = extent > 0.0 ? (point[axis] - box.lower[axis]) / extent : 0.0;
      if (!(unit > 0.0)) unit = 0.0;  // NaN where coordinates near overflow made extent infinite
      const auto cell = static_cast<std::uint64_t>(std::min(unit, 1.0) * kCells);
      code |= spreadBits(cell) << axis;
    }
    keys[i] = {code, static_cast<std::uint32_t>(i)};
  }
  std::sort(keys.begin(), keys.end());
  std::vector<std::uint32_t> order(count);
  for (std::size_t i = 0; i < count; ++i)
    order[i] = keys[i].second;
  return order;
}

}  // namespace delta::detail
