#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "query/detail/query_mesh_data.h"

namespace delta::detail {
namespace {

/// The float nearest `value` on its side: the largest float not above it (`down`) or the
/// smallest not below it, by std::nextafter.
float reference(double value, bool down) {
  const float f = static_cast<float>(value);
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  if (down && static_cast<double>(f) > value) return std::nextafter(f, -kInfinity);
  if (!down && static_cast<double>(f) < value) return std::nextafter(f, kInfinity);
  return f;
}

TEST(BoxOctet, BoundsRoundOutwardToTheNearestFloat) {
  // Coordinates where rounding to float is exact, inexact, at ±0, among float denormals, below
  // the smallest float denormal, and near the largest float.
  std::vector<double> values = {
      0.0,   -0.0,   1.0,    -1.0,    0.1,    -0.1,    1e-40,         -1e-40,
      1e-46, -1e-46, 1e-310, -1e-310, 3.4e38, -3.4e38, 1.0 + 0x1p-30, -(1.0 + 0x1p-30)};
  std::mt19937_64 random(7);
  for (int i = 0; i < 2000; ++i) {
    const double magnitude = std::ldexp(1.0, static_cast<int>(random() % 200) - 100);
    values.push_back((static_cast<double>(random() >> 11) * 0x1p-53 - 0.5) * magnitude);
  }
  std::vector<Aabb> boxes;
  for (std::size_t i = 0; i + 1 < values.size(); ++i) {
    const double a = values[i], b = values[i + 1];
    const Vec3 lower{std::min(a, b), std::min(b, -a), -std::abs(a)};
    const Vec3 upper{std::max(a, b), std::max(b, -a), std::abs(b)};
    boxes.push_back({lower, upper});
  }
  for (std::size_t first = 0; first < boxes.size(); first += kFanout) {
    const BoxOctet octet = octetOf(boxes, first, {});
    for (std::size_t i = 0; i < kFanout; ++i) {
      if (first + i >= boxes.size()) {  // empty slots lie infinitely far
        EXPECT_EQ(octet.lowerX[i], std::numeric_limits<float>::infinity());
        EXPECT_EQ(octet.upperZ[i], -std::numeric_limits<float>::infinity());
        continue;
      }
      const Aabb& box = boxes[first + i];
      const float lower[3] = {octet.lowerX[i], octet.lowerY[i], octet.lowerZ[i]};
      const float upper[3] = {octet.upperX[i], octet.upperY[i], octet.upperZ[i]};
      for (std::size_t axis = 0; axis < 3; ++axis) {
        ASSERT_EQ(lower[axis], reference(box.lower[axis], true)) << box.lower[axis];
        ASSERT_EQ(upper[axis], reference(box.upper[axis], false)) << box.upper[axis];
        ASSERT_LE(static_cast<double>(lower[axis]), box.lower[axis]);
        ASSERT_GE(static_cast<double>(upper[axis]), box.upper[axis]);
      }
      // Less an origin: the boxes less it, in double, rounded outward the same way.
      const Vec3 origin{1e8, -3.5, 0x1p-60};
      const BoxOctet shifted = octetOf(boxes, first, origin);
      const Vec3 low = box.lower - origin, high = box.upper - origin;
      ASSERT_EQ(shifted.lowerX[i], reference(low.x, true));
      ASSERT_EQ(shifted.lowerY[i], reference(low.y, true));
      ASSERT_EQ(shifted.lowerZ[i], reference(low.z, true));
      ASSERT_EQ(shifted.upperX[i], reference(high.x, false));
      ASSERT_EQ(shifted.upperY[i], reference(high.y, false));
      ASSERT_EQ(shifted.upperZ[i], reference(high.z, false));
    }
  }
}

}  // namespace
}  // namespace delta::detail
