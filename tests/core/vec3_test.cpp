// Vec3's scalar helpers where their arithmetic is not the obvious one.
#include "delta/core/vec3.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace delta {
namespace {

/// maxAbs as the library's fmax of the magnitudes (what it was before it was written out).
double fmaxOfMagnitudes(const Vec3& v) {
  return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
}

TEST(Vec3, MaxAbsIsFmaxOfTheMagnitudesBitForBit) {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const std::vector<double> special = {0.0,   -0.0,   1.0,  -1.0,  0x1p-1074, -0x1p-1074,
                                       1e300, -1e300, kInf, -kInf, kNaN,      -kNaN};
  std::size_t compared = 0;
  const auto expectSame = [&](const Vec3& v) {
    const double got = maxAbs(v), want = fmaxOfMagnitudes(v);
    if (std::isnan(want)) {
      EXPECT_TRUE(std::isnan(got)) << v.x << " " << v.y << " " << v.z;
    } else {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(got), std::bit_cast<std::uint64_t>(want))
          << v.x << " " << v.y << " " << v.z;
    }
    ++compared;
  };
  for (const double x : special)
    for (const double y : special)
      for (const double z : special)
        expectSame({x, y, z});
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> any(-1e3, 1e3);
  for (int i = 0; i < 10000; ++i)
    expectSame({any(random), any(random), any(random)});
  EXPECT_EQ(compared, special.size() * special.size() * special.size() + 10000);
  EXPECT_EQ(maxAbs({kNaN, 2.0, -3.0}), 3.0);  // a NaN passed over, as std::fmax does
  EXPECT_TRUE(std::isnan(maxAbs({kNaN, kNaN, kNaN})));
}

}  // namespace
}  // namespace delta
