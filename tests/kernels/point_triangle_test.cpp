#include "delta/kernels/point_triangle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "kernels/exact_distance.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

std::string pasteablePoint(const Vec3& p, const Triangle& t) {
  char text[512];
  std::snprintf(text, sizeof text,
                "closestPointOnTriangle({%.17g, %.17g, %.17g},\n"
                "                       {{%.17g, %.17g, %.17g}, {%.17g, %.17g, %.17g}, "
                "{%.17g, %.17g, %.17g}})",
                p.x, p.y, p.z, t.a.x, t.a.y, t.a.z, t.b.x, t.b.y, t.b.z, t.c.x, t.c.y, t.c.z);
  return text;
}

Vec3 fromBarycentrics(const Triangle& t, double u, double v) {
  return t.a + (t.b - t.a) * u + (t.c - t.a) * v;
}

struct Expected {
  Vec3 p;
  Vec3 closest;
  double distanceSquared;
  double u, v;
  TriangleFeature feature;
};

TEST(PointTriangle, EveryVoronoiRegion) {
  const Triangle t{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}};
  const Expected cases[] = {
      {{-1, -1, 1}, {0, 0, 0}, 3, 0, 0, TriangleFeature::VertexA},
      {{3, -1, 0}, {2, 0, 0}, 2, 1, 0, TriangleFeature::VertexB},
      {{-1, 3, 0}, {0, 2, 0}, 2, 0, 1, TriangleFeature::VertexC},
      {{1, -1, 2}, {1, 0, 0}, 5, 0.5, 0, TriangleFeature::EdgeAB},
      {{2, 2, 1}, {1, 1, 0}, 3, 0.5, 0.5, TriangleFeature::EdgeBC},
      {{-1, 1, 0}, {0, 1, 0}, 1, 0, 0.5, TriangleFeature::EdgeCA},
      {{0.5, 0.5, -3}, {0.5, 0.5, 0}, 9, 0.25, 0.25, TriangleFeature::Face},
      {{0.5, 1, 0}, {0.5, 1, 0}, 0, 0.25, 0.5, TriangleFeature::Face},  // on the face
      {{1, 0, 0}, {1, 0, 0}, 0, 0.5, 0, TriangleFeature::EdgeAB},       // on an edge
  };
  for (const Expected& e : cases) {
    SCOPED_TRACE(pasteablePoint(e.p, t));
    const PointTriangleResult r = closestPointOnTriangle(e.p, t);
    EXPECT_DOUBLE_EQ(r.distanceSquared, e.distanceSquared);
    EXPECT_NEAR(r.closest.x, e.closest.x, 1e-15);
    EXPECT_NEAR(r.closest.y, e.closest.y, 1e-15);
    EXPECT_NEAR(r.closest.z, e.closest.z, 1e-15);
    EXPECT_NEAR(r.u, e.u, 1e-15);
    EXPECT_NEAR(r.v, e.v, 1e-15);
    if (e.distanceSquared > 0) {
      EXPECT_EQ(r.feature, e.feature);
    }
  }
}

TEST(PointTriangle, OrientationDoesNotMatter) {
  const Triangle up{{0, 0, 0}, {2, 0, 0}, {0, 2, 0}}, down{{0, 0, 0}, {0, 2, 0}, {2, 0, 0}};
  for (const Vec3 p : {Vec3{0.5, 0.5, 1}, Vec3{0.5, 0.5, -1}, Vec3{3, 3, 3}}) {
    EXPECT_DOUBLE_EQ(closestPointOnTriangle(p, up).distanceSquared,
                     closestPointOnTriangle(p, down).distanceSquared);
  }
}

TEST(PointTriangle, ZeroAreaTriangleIsItsLongestEdge) {
  const Triangle collinear{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}};
  const PointTriangleResult r = closestPointOnTriangle({2, 1, 0}, collinear);
  EXPECT_EQ(r.distanceSquared, 1.0);
  EXPECT_EQ(r.closest, (Vec3{2, 0, 0}));
  EXPECT_NE(r.feature, TriangleFeature::Face);
  const Vec3 back = fromBarycentrics(collinear, r.u, r.v);
  EXPECT_NEAR(back.x, 2.0, 1e-15);
  EXPECT_GE(r.u, 0.0);
  EXPECT_GE(r.v, 0.0);
  EXPECT_LE(r.u + r.v, 1.0);
  // beyond the far end, and a repeated vertex
  EXPECT_EQ(closestPointOnTriangle({5, 0, 0}, collinear).distanceSquared, 4.0);
  const Triangle repeated{{0, 0, 0}, {0, 0, 0}, {0, 4, 0}};
  const PointTriangleResult s = closestPointOnTriangle({1, 2, 0}, repeated);
  EXPECT_EQ(s.distanceSquared, 1.0);
  EXPECT_EQ(s.closest, (Vec3{0, 2, 0}));
}

TEST(PointTriangle, PointTriangleIsAPoint) {
  const Triangle point{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  const PointTriangleResult r = closestPointOnTriangle({1, 1, 3}, point);
  EXPECT_EQ(r.distanceSquared, 4.0);
  EXPECT_EQ(r.closest, (Vec3{1, 1, 1}));
  EXPECT_EQ(r.feature, TriangleFeature::VertexA);
  EXPECT_EQ(closestPointOnTriangle({1, 1, 1}, point).distanceSquared, 0.0);
}

TEST(PointTriangle, SliverFaceIsExact) {
  // Height 1e-10 of the length: a plain cross product tilts this face by 1e-6 rad.
  const Triangle needle{{0.1, 0.2, 0.3}, {1.1, 0.7, -0.4}, {0.6, 0.45 + 1e-10, -0.05}};
  test::PairRandom random(3);
  for (int i = 0; i < 2000; ++i) {
    const double u = random.uniform(), v = random.uniform() * (1 - u);
    const Vec3 p = fromBarycentrics(needle, u, v) + random.unitVector() * random.uniform(0, 1e-3);
    const PointTriangleResult r = closestPointOnTriangle(p, needle);
    const double exact = std::sqrt(test::exactSquaredDistance(p, needle));
    ASSERT_NEAR(std::sqrt(r.distanceSquared), exact, 1e-15) << pasteablePoint(p, needle);
  }
}

TEST(PointTriangle, NeedlesAreMeasuredToTheirTips) {
  // A needle 1 long whose third corner lies h off its middle, its edges' lines meeting at its
  // tips at angles of about 2h: a point just beyond a tip projects within rounding of both lines.
  // The face test took such a point for one over the face, and measured it to the plane: 1.0e-11
  // for a point 2.9e-11 from the tip of a needle 1e-12 high (found by an audit, with this
  // sweep: up to 7.7e6 ε·(L + d) off at h = 1e-9).
  test::PairRandom random(5);
  for (const double height : {1e-3, 1e-6, 1e-9, 1e-12}) {
    double worst = 0.0;
    for (std::size_t i = 0; i < test::scaledCount(4000); ++i) {
      const Vec3 a = random.inCube(1.0), along = normalized(random.unitVector());
      const Vec3 across = normalized(cross(along, random.unitVector()));
      const Triangle needle{a, a + along, a + along * 0.5 + across * height};
      const Vec3 tip = random.below(2) == 0 ? needle.a : needle.b;
      const double reach = height * std::pow(10.0, random.uniform(-2, 2));
      const Vec3 normal = normalized(needle.areaVector());
      const Vec3 p = i % 2 == 0 ? tip + random.unitVector() * reach
                                : needle.b + (needle.b - needle.a) * (reach * random.uniform()) +
                                      normal * (random.uniform(-20, 20) * reach);
      const double exact = std::sqrt(test::exactSquaredDistance(p, needle));
      const double error =
          std::fabs(std::sqrt(closestPointOnTriangle(p, needle).distanceSquared) - exact) /
          (kEpsilon * (1.0 + exact));
      worst = std::max(worst, error);
      ASSERT_LE(error, 16.0) << "height " << height << "\n" << pasteablePoint(p, needle);
    }
    std::printf("[ stats    ] needles %-8g: max |d - exact| = %.3g eps (L + d)\n", height, worst);
  }
}

TEST(PointTriangle, PointsOverANeedleNearItsShortEdgeAreOverTheFace) {
  // One rounding bound for the three edges' areas (the longest edge's) took points over a
  // needle's face within 1e-13·L²/h of its short edge (h long) for points off it, and measured
  // them to a long edge: 1.0e-8 for a point 1e-12 above the face, 1e-8 in from the short edge
  // (an audit's case).
  const Triangle needle{{0, 0, 0}, {1, 0, 0}, {1, 0x1.ad7f29abcaf48p-24, 0}};  // h = 1e-7
  const Vec3 p{0x1.ffffffaa19c47p-1, 0x1.ad7f29abcaf48p-25, 0x1.19799812dea11p-40};
  const PointTriangleResult r = closestPointOnTriangle(p, needle);
  EXPECT_EQ(r.feature, TriangleFeature::Face);
  EXPECT_NEAR(std::sqrt(r.distanceSquared), std::sqrt(test::exactSquaredDistance(p, needle)),
              1e-16);
  test::PairRandom random(6);
  for (const double height : {1e-5, 1e-7, 1e-9, 1e-11}) {
    for (int i = 0; i < 200; ++i) {
      const Triangle t{{0, 0, 0}, {1, 0, 0}, {1, height, 0}};
      const Vec3 q{1 - height * random.uniform(0.01, 0.9), height * random.uniform(0.0, 0.005),
                   random.uniform(-1e-9, 1e-9)};
      const double exact = std::sqrt(test::exactSquaredDistance(q, t));
      ASSERT_LE(std::fabs(std::sqrt(closestPointOnTriangle(q, t).distanceSquared) - exact),
                16.0 * kEpsilon * (1.0 + exact))
          << height << "\n"
          << pasteablePoint(q, t);
    }
  }
}

TEST(PointTriangle, PointsWhoseProjectionLiesWithinRoundingOfAnEdgeAreExact) {
  // Where the rounded areas leave the projection within their rounding of an edge's line, the
  // edges answered: for a point over the face there, its distance to that edge, up to 783·ε·(size
  // + d) too far on this sweep (points within 600ε·(|a| + 2L) of an edge's line, on either side,
  // at heights from 0 to that band's width, triangles turned at offsets up to 1e3). Now exact signs
  // decide the side, and either answer is the plane's or the edge's to a few ε.
  test::PairRandom random(7);
  double worst = 0.0;
  for (std::size_t i = 0; i < test::scaledCount(20000); ++i) {
    const double offset = std::pow(10.0, random.uniform(0, 3));
    const double length = std::pow(10.0, random.uniform(-1, 1));
    const Vec3 a = random.unitVector() * offset;
    const Triangle t{a, a + random.unitVector() * length,
                     a + random.unitVector() * (length * random.uniform(0.05, 1.05))};
    const Vec3 corner[3] = {t.a, t.b, t.c};
    const Vec3 start = corner[i % 3], edge = corner[(i + 1) % 3] - start;
    const Vec3 normal = normalized(t.areaVector());
    const Vec3 inward = normalized(cross(normal, edge));
    const double band = 600.0 * kEpsilon * (offset + 2.0 * length);
    const double height = i % 7 == 0 ? 0.0 : band * std::pow(10.0, random.uniform(-4, 0));
    const Vec3 p = start + edge * random.uniform(0.05, 0.95) +
                   inward * (band * random.uniform(-0.1, 1.1)) +
                   normal * (random.below(2) == 0 ? height : -height);
    const double exact = std::sqrt(test::exactSquaredDistance(p, t));
    const double size = std::max(length, std::sqrt(lengthSquared(p - t.a)));
    const double error =
        std::fabs(std::sqrt(closestPointOnTriangle(p, t).distanceSquared) - exact) /
        (kEpsilon * (size + exact));
    worst = std::max(worst, error);
    ASSERT_LE(error, 16.0) << pasteablePoint(p, t);
  }
  std::printf("[ stats    ] beside an edge: max |d - exact| = %.3g eps (size + d)\n", worst);
}

TEST(PointTriangle, AtScaleTheBandBesideAnEdgeIsDecidedAsTheKernelDecidesIt) {
  // Found by the sanitizer build's point query on fandisk: a point in a face's plane (y the
  // same for all four), inside the face within rounding of an edge's line. The kernel's exact
  // signs on the given coordinates put it inside (distance 0); distanceAtScale, which runs the
  // kernel on the rounded differences from the first corner, decided on those and measured it
  // to the edge: 1.9e-18.
  const Triangle face{{-0x1.0cb295e9e1b09p-8, 0x1.05aee631f8a09p-2, 0x1.5182a9930be0ep-7},
                      {0x1.8e219652bd3c3p-6, 0x1.05aee631f8a09p-2, 0x1.a36e2eb1c432dp-9},
                      {0x1.ff2e48e8a71dep-8, 0x1.05aee631f8a09p-2, -0x1.82a9930be0dedp-7}};
  const Vec3 p{0x1.4af4f0d844d01p-7, 0x1.05aee631f8a09p-2, 0x1.ba5e353f7ced9p-8};
  EXPECT_EQ(closestPointOnTriangle(p, face).distanceSquared, 0.0);
  EXPECT_EQ(distanceAtScale(p, face), 0.0);
  // Points in the plane of axis-aligned faces, within 600ε of an edge's line on either side: the
  // two forms agree bit for bit (no square here is subnormal).
  test::PairRandom random(31);
  for (std::size_t i = 0; i < test::scaledCount(20000); ++i) {
    const double y = random.uniform(-1, 1);
    const auto inPlane = [&] { return Vec3{random.uniform(-1, 1), y, random.uniform(-1, 1)}; };
    const Triangle t{inPlane(), inPlane(), inPlane()};
    const Vec3 corner[3] = {t.a, t.b, t.c};
    const Vec3 start = corner[i % 3], edge = corner[(i + 1) % 3] - start;
    const Vec3 across = normalized(Vec3{-edge.z, 0, edge.x});
    Vec3 q = start + edge * random.uniform(0.05, 0.95) +
             across * (600.0 * kEpsilon * random.uniform(-1, 1));
    q.y = y;
    const double kernel = std::sqrt(closestPointOnTriangle(q, t).distanceSquared);
    ASSERT_EQ(distanceAtScale(q, t), kernel) << pasteablePoint(q, t);
  }
}

TEST(PointTriangle, FarFromTheOriginAsAccurateAsNearIt) {
  const Vec3 o{-1e6, 2e6, 3e6};
  const Triangle t{o, o + Vec3{2, 0, 0}, o + Vec3{0, 2, 0}};
  const PointTriangleResult r = closestPointOnTriangle(o + Vec3{0.5, 0.5, 0.25}, t);
  EXPECT_DOUBLE_EQ(r.distanceSquared, 0.0625);
  EXPECT_EQ(r.feature, TriangleFeature::Face);
  EXPECT_DOUBLE_EQ(r.u, 0.25);
}

/// The vertices and centroid of B, and random points around A, against the exact distance, on
/// every family; the closest point must lie on the triangle and match its barycentrics.
TEST(PointTriangle, MatchesExactDistanceOnEveryFamily) {
  test::PairRandom random(17);
  for (const auto family : test::kAllFamilies) {
    double worst = 0.0;
    int failures = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(1000), 9)) {
      const double size = test::pairSize(a, b);
      const Vec3 queries[] = {b.a,
                              b.b,
                              b.c,
                              b.centroid(),
                              a.centroid() + random.inCube(size),
                              a.a + random.inCube(0.1 * size)};
      const double twiceArea = length(cross(a.b - a.a, a.c - a.a));
      const double longest = std::max({distance(a.a, a.b), distance(a.b, a.c), distance(a.c, a.a)});
      // Barycentrics of a thin triangle are ill-conditioned (ε·L/h): check them only when
      // the triangle is not a needle.
      const bool wellShaped = twiceArea > 1e-3 * longest * longest;
      for (const Vec3& p : queries) {
        const PointTriangleResult r = closestPointOnTriangle(p, a);
        ASSERT_TRUE(std::isfinite(r.distanceSquared) && isFinite(r.closest) && std::isfinite(r.u) &&
                    std::isfinite(r.v))
            << pasteablePoint(p, a);
        const double exact = std::sqrt(test::exactSquaredDistance(p, a));
        const double error = std::fabs(std::sqrt(r.distanceSquared) - exact) / size;
        worst = std::max(worst, error);
        const double rounding = 4 * kEpsilon * std::max(maxAbs(p), maxAbs(r.closest));
        const double off = std::sqrt(test::exactSquaredDistance(r.closest, a));
        const double consistency = std::fabs(distance(p, r.closest) - std::sqrt(r.distanceSquared));
        const double reconstruction = distance(fromBarycentrics(a, r.u, r.v), r.closest);
        const bool ok = error <= 1e-12 && off <= 1e-12 * size + rounding &&
                        consistency <= 1e-12 * size + rounding && r.u >= 0 && r.v >= 0 &&
                        r.u + r.v <= 1 + 4 * kEpsilon &&
                        (!wellShaped || reconstruction <= 1e-12 * size + rounding);
        if (!ok && failures++ < 3)
          ADD_FAILURE() << test::name(family) << ": error " << error << ", off " << off
                        << ", |p-closest| vs d " << consistency << ", u " << r.u << ", v " << r.v
                        << ", reconstruction " << reconstruction << " for\n"
                        << pasteablePoint(p, a);
      }
    }
    std::printf("[ stats    ] %-20s point-triangle: max |d - exact| / size = %.3g\n",
                test::name(family), worst);
  }
}

}  // namespace
}  // namespace delta::kernels
