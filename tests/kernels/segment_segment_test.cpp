#include "delta/kernels/segment_segment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "kernels/exact_distance.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

using test::exactSquaredDistance;
using test::PairRandom;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

std::string pasteableSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  char text[512];
  std::snprintf(text, sizeof text,
                "closestPointsOnSegments({%.17g, %.17g, %.17g}, {%.17g, %.17g, %.17g},\n"
                "                        {%.17g, %.17g, %.17g}, {%.17g, %.17g, %.17g})",
                p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, q0.x, q0.y, q0.z, q1.x, q1.y, q1.z);
  return text;
}

void expectNear(const Vec3& actual, const Vec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

TEST(SegmentSegment, CrossingSkewSegments) {
  const auto r = closestPointsOnSegments({-1, 0, 0}, {1, 0, 0}, {0, -1, 1}, {0, 1, 1});
  EXPECT_DOUBLE_EQ(r.distanceSquared, 1.0);
  EXPECT_DOUBLE_EQ(r.s, 0.5);
  EXPECT_DOUBLE_EQ(r.t, 0.5);
  expectNear(r.p, {0, 0, 0}, 1e-15);
  expectNear(r.q, {0, 0, 1}, 1e-15);
}

TEST(SegmentSegment, IntersectingSegmentsHaveDistanceZero) {
  const auto r = closestPointsOnSegments({0, 0, 0}, {2, 2, 0}, {0, 2, 0}, {2, 0, 0});
  EXPECT_EQ(r.distanceSquared, 0.0);
  expectNear(r.p, {1, 1, 0}, 1e-15);
  expectNear(r.q, {1, 1, 0}, 1e-15);
}

TEST(SegmentSegment, EndpointToEndpoint) {
  const auto r = closestPointsOnSegments({0, 0, 0}, {1, 0, 0}, {2, 1, 0}, {3, 5, 0});
  EXPECT_DOUBLE_EQ(r.distanceSquared, 2.0);
  EXPECT_EQ(r.s, 1.0);
  EXPECT_EQ(r.t, 0.0);
  EXPECT_EQ(r.p, (Vec3{1, 0, 0}));
  EXPECT_EQ(r.q, (Vec3{2, 1, 0}));
}

TEST(SegmentSegment, EndpointToInterior) {
  const auto r = closestPointsOnSegments({0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {1, 3, 5});
  EXPECT_DOUBLE_EQ(r.distanceSquared, 1.0);
  EXPECT_DOUBLE_EQ(r.s, 0.5);
  EXPECT_EQ(r.t, 0.0);
  // and the other way round
  const auto swapped = closestPointsOnSegments({1, 1, 0}, {1, 3, 5}, {0, 0, 0}, {2, 0, 0});
  EXPECT_DOUBLE_EQ(swapped.distanceSquared, 1.0);
  EXPECT_EQ(swapped.s, 0.0);
  EXPECT_DOUBLE_EQ(swapped.t, 0.5);
}

TEST(SegmentSegment, ParallelOverlappingGiveOneClosestPair) {
  for (const bool reversed : {false, true}) {
    const Vec3 q0{1, 1, 0}, q1{3, 1, 0};
    const auto r = reversed ? closestPointsOnSegments({0, 0, 0}, {2, 0, 0}, q1, q0)
                            : closestPointsOnSegments({0, 0, 0}, {2, 0, 0}, q0, q1);
    EXPECT_DOUBLE_EQ(r.distanceSquared, 1.0);
    EXPECT_DOUBLE_EQ(distanceSquared(r.p, r.q), 1.0);
    EXPECT_NEAR(r.p.x, r.q.x, 1e-15);  // a pair straight across, in the overlap [1, 2]
    EXPECT_GE(r.p.x, 1.0 - 1e-15);
    EXPECT_LE(r.p.x, 2.0 + 1e-15);
    EXPECT_GE(r.s, 0.0);
    EXPECT_LE(r.s, 1.0);
    EXPECT_GE(r.t, 0.0);
    EXPECT_LE(r.t, 1.0);
  }
}

TEST(SegmentSegment, CollinearDisjointAndOverlapping) {
  const auto apart = closestPointsOnSegments({0, 0, 0}, {1, 0, 0}, {3, 0, 0}, {5, 0, 0});
  EXPECT_DOUBLE_EQ(apart.distanceSquared, 4.0);
  EXPECT_EQ(apart.s, 1.0);
  EXPECT_EQ(apart.t, 0.0);
  const auto reversed = closestPointsOnSegments({0, 0, 0}, {1, 0, 0}, {5, 0, 0}, {3, 0, 0});
  EXPECT_DOUBLE_EQ(reversed.distanceSquared, 4.0);
  EXPECT_EQ(reversed.t, 1.0);
  const auto overlapping = closestPointsOnSegments({0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {5, 0, 0});
  EXPECT_EQ(overlapping.distanceSquared, 0.0);
}

TEST(SegmentSegment, ZeroLengthSegmentsArePoints) {
  const auto both = closestPointsOnSegments({1, 2, 3}, {1, 2, 3}, {1, 2, 5}, {1, 2, 5});
  EXPECT_EQ(both.distanceSquared, 4.0);
  EXPECT_EQ(both.p, (Vec3{1, 2, 3}));
  EXPECT_EQ(both.q, (Vec3{1, 2, 5}));
  const auto first = closestPointsOnSegments({0, 1, 0}, {0, 1, 0}, {-1, 0, 0}, {1, 0, 0});
  EXPECT_EQ(first.distanceSquared, 1.0);
  EXPECT_EQ(first.t, 0.5);
  EXPECT_EQ(first.q, (Vec3{0, 0, 0}));
  const auto second = closestPointsOnSegments({-1, 0, 0}, {1, 0, 0}, {3, 4, 0}, {3, 4, 0});
  EXPECT_EQ(second.distanceSquared, 16.0 + 4.0);
  EXPECT_EQ(second.s, 1.0);
  const auto same = closestPointsOnSegments({1, 1, 1}, {1, 1, 1}, {1, 1, 1}, {1, 1, 1});
  EXPECT_EQ(same.distanceSquared, 0.0);
}

TEST(SegmentSegment, FarFromTheOriginAsAccurateAsNearIt) {
  const Vec3 o{1e6, -3e6, 2.5e6};
  const auto r = closestPointsOnSegments(o + Vec3{-1, 0, 0}, o + Vec3{1, 0, 0},
                                         o + Vec3{0, -1, 1e-3}, o + Vec3{0, 1, 1e-3});
  // 1e-3 rounds at 2.5e6 to a spacing of 4.7e-10; the distance is that of the stored inputs.
  const double z = (o.z + 1e-3) - o.z;
  EXPECT_DOUBLE_EQ(std::sqrt(r.distanceSquared), z);
}

TEST(SegmentSegment, NearParallelSegmentsAreAccurate) {
  // The classic weak spot: the Gram determinant |d1|²|d2|² − (d1·d2)² cancels completely.
  PairRandom random(11);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p0 = random.inCube(1), d1 = random.unitVector() * random.uniform(0.1, 1);
    const double angle = std::pow(10.0, -random.uniform(0, 16));
    const Vec3 d2 = (d1 + test::detail::orthogonal(normalized(d1)) * (length(d1) * angle)) *
                    (random.below(2) == 0 ? random.uniform(0.2, 2) : -random.uniform(0.2, 2));
    const Vec3 q0 = p0 + d1 * random.uniform(-1.5, 1.5) + random.inCube(1e-3 * random.uniform());
    const Vec3 p1 = p0 + d1, q1 = q0 + d2;
    const auto r = closestPointsOnSegments(p0, p1, q0, q1);
    const double exact = std::sqrt(exactSquaredDistance(p0, p1, q0, q1));
    const double size = std::max(length(p1 - p0), length(q1 - q0));
    const double error = std::fabs(std::sqrt(r.distanceSquared) - exact) / size;
    worst = std::max(worst, error);
    if (error > 1e-12) {
      ADD_FAILURE() << "error " << error << " for\n" << pasteableSegments(p0, p1, q0, q1);
      break;
    }
  }
  std::printf("[ stats    ] near-parallel segments: max |d - exact| / size = %.3g\n", worst);
}

/// Every edge pair of every family's triangle pairs, against the exact distance.
TEST(SegmentSegment, EdgesOfEveryFamilyMatchExactDistance) {
  for (const auto family : test::kAllFamilies) {
    double worst = 0.0;
    int failures = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(600), 5)) {
      const Vec3 va[3] = {a.a, a.b, a.c}, vb[3] = {b.a, b.b, b.c};
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          const Vec3 &p0 = va[i], &p1 = va[(i + 1) % 3], &q0 = vb[j], &q1 = vb[(j + 1) % 3];
          const auto r = closestPointsOnSegments(p0, p1, q0, q1);
          ASSERT_TRUE(std::isfinite(r.distanceSquared) && isFinite(r.p) && isFinite(r.q));
          const double size = test::pairSize(a, b);
          const double exact = std::sqrt(exactSquaredDistance(p0, p1, q0, q1));
          const double error = std::fabs(std::sqrt(r.distanceSquared) - exact) / size;
          worst = std::max(worst, error);
          // p, q on their segments, and the reported distance is theirs (to coordinate rounding)
          const double rounding = 4 * kEpsilon * std::max(maxAbs(r.p), maxAbs(r.q));
          const double onP = std::sqrt(exactSquaredDistance(r.p, r.p, p0, p1));
          const double onQ = std::sqrt(exactSquaredDistance(r.q, r.q, q0, q1));
          const double consistency = std::fabs(distance(r.p, r.q) - std::sqrt(r.distanceSquared));
          const bool ok = error <= 1e-12 && r.s >= 0 && r.s <= 1 && r.t >= 0 && r.t <= 1 &&
                          onP <= 1e-12 * size + rounding && onQ <= 1e-12 * size + rounding &&
                          consistency <= 1e-12 * size + 2 * rounding;
          if (!ok && failures++ < 3)
            ADD_FAILURE() << test::name(family) << ": error " << error << ", s " << r.s << ", t "
                          << r.t << ", off p " << onP << ", off q " << onQ << ", |p-q| vs d "
                          << consistency << " for\n"
                          << pasteableSegments(p0, p1, q0, q1);
        }
      }
    }
    std::printf("[ stats    ] %-20s edge pairs: max |d - exact| / size = %.3g\n",
                test::name(family), worst);
  }
}

TEST(SegmentSegment, SymmetricInItsArguments) {
  for (const auto& [a, b] : test::makePairs(test::PairFamily::ParallelEdges, 2000, 3)) {
    const auto r = closestPointsOnSegments(a.a, a.b, b.a, b.b);
    const auto swapped = closestPointsOnSegments(b.a, b.b, a.a, a.b);
    EXPECT_NEAR(std::sqrt(r.distanceSquared), std::sqrt(swapped.distanceSquared),
                1e-12 * test::pairSize(a, b))
        << pasteableSegments(a.a, a.b, b.a, b.b);
  }
}

}  // namespace
}  // namespace delta::kernels
