#include "delta/core/aabb.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace delta {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// The squared distance from p to the box by clamping p into it (the definition).
double clampedDistanceSquared(const Vec3& p, const Aabb& box) {
  const Vec3 nearest = min(max(p, box.lower), box.upper);
  return lengthSquared(p - nearest);
}

TEST(Aabb, PointDistanceIsTheClampedPointsOnRandomAndEdgeCases) {
  const Aabb box{{-1, 2, 0.5}, {3, 2.5, 7}};
  EXPECT_EQ(distanceSquared(Vec3{0, 2.2, 1}, box), 0.0);         // inside
  EXPECT_EQ(distanceSquared(Vec3{3, 2.5, 7}, box), 0.0);         // a corner
  EXPECT_EQ(distanceSquared(Vec3{-1, 2.2, 1}, box), 0.0);        // a face
  EXPECT_EQ(distanceSquared(Vec3{-3, 2.2, 1}, box), 4.0);        // beyond one face
  EXPECT_EQ(distanceSquared(Vec3{-3, 0, 1}, box), 8.0);          // beyond an edge
  EXPECT_EQ(distanceSquared(Vec3{-3, 0, 8}, box), 9.0);          // beyond a corner
  EXPECT_EQ(distanceSquared(Vec3{0, 0, 0}, Aabb{}), kInfinity);  // the empty box
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> coordinate(-10.0, 10.0);
  for (int i = 0; i < 10000; ++i) {
    const Vec3 p{coordinate(random), coordinate(random), coordinate(random)};
    EXPECT_EQ(distanceSquared(p, box), clampedDistanceSquared(p, box)) << i;
  }
}

TEST(Aabb, BoxDistanceAndApart) {
  const Aabb a{{0, 0, 0}, {1, 1, 1}};
  EXPECT_EQ(distanceSquared(a, Aabb{{0.5, 0.5, 0.5}, {2, 2, 2}}), 0.0);  // overlapping
  EXPECT_EQ(distanceSquared(a, Aabb{{1, 0, 0}, {2, 1, 1}}), 0.0);        // touching
  EXPECT_EQ(distanceSquared(a, Aabb{{3, 4, 0}, {5, 5, 1}}), 4.0 + 9.0);
  EXPECT_EQ(distanceSquared(a, Aabb{}), kInfinity);
  EXPECT_TRUE(apart(a, Aabb{{3, 0, 0}, {4, 1, 1}}, 2.0));
  EXPECT_FALSE(apart(a, Aabb{{3, 0, 0}, {4, 1, 1}}, 2.5));
  EXPECT_TRUE(apart(a, Aabb{{1, 0, 0}, {2, 1, 1}}, 0.0));  // touching: apart by 0
  EXPECT_TRUE(apart(a, Aabb{}, 1e300));
}

TEST(Aabb, LongestAxisTakesTheLowestOfEqualExtents) {
  EXPECT_EQ(longestAxis(Aabb{{0, 0, 0}, {1, 3, 2}}), 1);
  EXPECT_EQ(longestAxis(Aabb{{0, 0, 0}, {1, 1, 5}}), 2);
  EXPECT_EQ(longestAxis(Aabb{{0, 0, 0}, {2, 2, 2}}), 0);  // a cube: x
  EXPECT_EQ(longestAxis(Aabb{{0, 0, 0}, {1, 4, 4}}), 1);  // y and z tie: y
  EXPECT_EQ(longestAxis(Aabb{{5, 5, 5}, {5, 5, 5}}), 0);  // a point
}

TEST(Aabb, IntersectionIsWhatBothHold) {
  const Aabb a{{0, 0, 0}, {2, 2, 2}};
  const Aabb both = intersection(a, Aabb{{1, -1, 1.5}, {3, 1, 4}});
  EXPECT_EQ(both.lower, (Vec3{1, 0, 1.5}));
  EXPECT_EQ(both.upper, (Vec3{2, 1, 2}));
  EXPECT_TRUE(intersection(a, Aabb{{3, 0, 0}, {4, 1, 1}}).empty());  // apart
  const Aabb face = intersection(a, Aabb{{2, 0, 0}, {3, 2, 2}});     // a shared face: flat
  EXPECT_FALSE(face.empty());
  EXPECT_EQ(face.extent().x, 0.0);
  EXPECT_TRUE(intersection(a, Aabb{}).empty());
}

}  // namespace
}  // namespace delta
