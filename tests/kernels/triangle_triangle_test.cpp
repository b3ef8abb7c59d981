#include "delta/kernels/triangle_triangle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "delta/core/rotation.h"

#include "kernels/exact_distance.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

using test::exactIntersect;
using test::exactSquaredDistance;
using test::name;
using test::PairFamily;
using test::pairSize;
using test::pasteable;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
/// The accuracy every result is held to, relative to the pair's size (its longest edge).
constexpr double kTolerance = 1e-12;

Vec3 fromBarycentrics(const Triangle& t, double u, double v) {
  return t.a + (t.b - t.a) * u + (t.c - t.a) * v;
}

double distanceOf(const TriangleDistanceResult& r) {
  return std::sqrt(r.distanceSquared);
}

/// Rounding of output coordinates: far from the origin, points cannot be closer to exact than
/// their own spacing (about 1e-10 at 1e6).
double coordinateRounding(const TriangleDistanceResult& r) {
  return 4 * kEpsilon * std::max(maxAbs(r.p), maxAbs(r.q));
}

// ---------------------------------------------------------------------------------------------
// Hand cases with known answers.

const Triangle kUnit{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

TEST(TriangleDistance, ParallelFacesOneAbove) {
  const Triangle above{{0.1, 0.1, 2}, {0.3, 0.1, 2}, {0.1, 0.3, 2}};
  const auto r = triangleDistanceBruteForce(kUnit, above);
  EXPECT_DOUBLE_EQ(r.distanceSquared, 4.0);
  EXPECT_FALSE(r.intersect);
  EXPECT_DOUBLE_EQ(r.p.z, 0.0);
  EXPECT_DOUBLE_EQ(r.q.z, 2.0);
  EXPECT_NEAR(r.p.x, r.q.x, 1e-15);
  EXPECT_NEAR(r.p.y, r.q.y, 1e-15);
}

TEST(TriangleDistance, VertexAboveFace) {
  const Triangle spike{{0.25, 0.25, 0.5}, {0, 0, 3}, {1, 1, 3}};
  const auto r = triangleDistanceBruteForce(kUnit, spike);
  EXPECT_DOUBLE_EQ(r.distanceSquared, 0.25);
  EXPECT_NEAR(r.a1, 0.25, 1e-15);
  EXPECT_NEAR(r.a2, 0.25, 1e-15);
  EXPECT_EQ(r.a3, 0.0);  // B's vertex a
  EXPECT_EQ(r.a4, 0.0);
  EXPECT_EQ(r.q, spike.a);
}

TEST(TriangleDistance, SkewEdges) {
  // B stands in the plane x = 0.5 below A's edge ab; its edge ab crosses A's at distance 1.
  const Triangle b{{0.5, -1, -1}, {0.5, -1, 1}, {0.5, -3, 0}};
  const auto r = triangleDistanceBruteForce(kUnit, b);
  EXPECT_DOUBLE_EQ(r.distanceSquared, 1.0);
  EXPECT_FALSE(r.intersect);
  EXPECT_NEAR(distance(r.p, {0.5, 0, 0}), 0.0, 1e-15);
  EXPECT_NEAR(distance(r.q, {0.5, -1, 0}), 0.0, 1e-15);
  EXPECT_NEAR(r.a1, 0.5, 1e-15);
  EXPECT_NEAR(r.a2, 0.0, 1e-15);
  EXPECT_NEAR(r.a3, 0.5, 1e-15);
  EXPECT_NEAR(r.a4, 0.0, 1e-15);
}

TEST(TriangleDistance, EdgePiercingFaceIntersectsOnTheSegment) {
  // B's edge from (0.2, 0.2, -1) to (0.2, 0.2, 1) pierces A's interior; B's other vertex is
  // above, so the intersection is a segment from (0.2, 0.2, 0) along B's plane y = 0.2.
  const Triangle b{{0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.6, 0.2, 1}};
  const auto r = triangleDistanceBruteForce(kUnit, b);
  EXPECT_TRUE(r.intersect);
  EXPECT_EQ(r.distanceSquared, 0.0);
  EXPECT_EQ(r.p, r.q);
  // The intersection segment runs from (0.2, 0.2, 0) to (0.4, 0.2, 0): its midpoint.
  EXPECT_NEAR(r.p.x, 0.3, 1e-15);
  EXPECT_NEAR(r.p.y, 0.2, 1e-15);
  EXPECT_NEAR(r.p.z, 0.0, 1e-15);
  EXPECT_NEAR(distance(fromBarycentrics(kUnit, r.a1, r.a2), r.p), 0.0, 1e-15);
  EXPECT_NEAR(distance(fromBarycentrics(b, r.a3, r.a4), r.p), 0.0, 1e-15);
  EXPECT_TRUE(trianglesIntersect(kUnit, b));
  EXPECT_TRUE(trianglesIntersect(b, kUnit));
}

TEST(TriangleDistance, CrossingTrianglesIntersectAtTheMiddleOfTheirCommonSegment) {
  // Two triangles crossing like links of a chain.
  const Triangle a{{-1, 0, -1}, {1, 0, -1}, {0, 0, 1}};
  const Triangle b{{0, -1, 0}, {0, 1, 0}, {0, 0, 2}};
  const auto r = triangleDistanceBruteForce(a, b);
  EXPECT_TRUE(r.intersect);
  // Common segment: x = 0, y = 0, z from 0 (B's lowest point on A) to 1 (A's apex).
  EXPECT_NEAR(r.p.x, 0.0, 1e-15);
  EXPECT_NEAR(r.p.y, 0.0, 1e-15);
  EXPECT_NEAR(r.p.z, 0.5, 1e-15);
}

TEST(TriangleDistance, CoplanarOverlappingGivesAPointOfTheOverlap) {
  const Triangle b{{0.2, 0.2, 0}, {2, 0.2, 0}, {0.2, 2, 0}};
  const auto r = triangleDistanceBruteForce(kUnit, b);
  EXPECT_TRUE(r.intersect);
  EXPECT_EQ(r.distanceSquared, 0.0);
  // The overlap is the triangle (0.2, 0.2), (0.8, 0.2), (0.2, 0.8).
  EXPECT_GE(r.p.x, 0.2 - 1e-15);
  EXPECT_GE(r.p.y, 0.2 - 1e-15);
  EXPECT_LE(r.p.x + r.p.y, 1.0 + 1e-15);
  EXPECT_EQ(r.p.z, 0.0);
}

TEST(TriangleDistance, CoplanarDisjoint) {
  const Triangle b{{1, 1, 0}, {3, 1, 0}, {1, 3, 0}};
  const auto r = triangleDistanceBruteForce(kUnit, b);
  EXPECT_FALSE(r.intersect);
  EXPECT_DOUBLE_EQ(r.distanceSquared, 0.5);  // from (1, 1) to the line x + y = 1
  EXPECT_NEAR(r.p.x, 0.5, 1e-15);
  EXPECT_EQ(r.q, b.a);
}

TEST(TriangleDistance, TouchingCountsAsIntersecting) {
  const Triangle atVertex{{1, 0, 0}, {2, 0, 1}, {2, 1, 1}};            // shares vertex b
  const Triangle onEdge{{0.5, 0.5, 0}, {1, 1, 1}, {2, 1, 0}};          // vertex on edge bc
  const Triangle onFace{{0.25, 0.25, 0}, {0, 0, 1}, {1, 1, 1}};        // vertex on the face
  const Triangle edgeOnEdge{{0.5, -1, 0}, {0.5, -1, 1}, {0.5, 0, 0}};  // vertex on edge ab
  for (const Triangle& b : {atVertex, onEdge, onFace, edgeOnEdge}) {
    SCOPED_TRACE(pasteable(kUnit, b));
    const auto r = triangleDistanceBruteForce(kUnit, b);
    EXPECT_TRUE(r.intersect);
    EXPECT_EQ(r.distanceSquared, 0.0);
    EXPECT_TRUE(trianglesIntersect(kUnit, b));
    EXPECT_TRUE(exactIntersect(kUnit, b));
  }
  const auto r = triangleDistanceBruteForce(kUnit, atVertex);
  EXPECT_NEAR(distance(r.p, {1, 0, 0}), 0.0, 1e-15);
}

TEST(TriangleDistance, ZeroAreaTrianglesAreSegmentsAndPoints) {
  const Triangle segment{{0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.2, 0.2, 0.5}};  // pierces kUnit
  const auto pierce = triangleDistanceBruteForce(kUnit, segment);
  EXPECT_TRUE(pierce.intersect);
  EXPECT_NEAR(distance(pierce.p, {0.2, 0.2, 0}), 0.0, 1e-15);
  const Triangle point{{0.2, 0.2, 3}, {0.2, 0.2, 3}, {0.2, 0.2, 3}};
  const auto above = triangleDistanceBruteForce(kUnit, point);
  EXPECT_FALSE(above.intersect);
  EXPECT_EQ(above.distanceSquared, 9.0);
  const auto both = triangleDistanceBruteForce(point, {{1, 2, 3}, {1, 2, 3}, {1, 2, 3}});
  EXPECT_DOUBLE_EQ(both.distanceSquared, 0.64 + 3.24);
  const Triangle crossing{{0, 0, 0}, {2, 2, 0}, {1, 1, 0}};  // a segment on the diagonal
  const Triangle other{{0, 2, 0}, {2, 0, 0}, {2, 0, 0}};     // and across it
  EXPECT_TRUE(triangleDistanceBruteForce(crossing, other).intersect);
  EXPECT_TRUE(trianglesIntersect(crossing, other));
  const Triangle skew{{0, 2, 1}, {2, 0, 1}, {2, 0, 1}};
  EXPECT_DOUBLE_EQ(triangleDistanceBruteForce(crossing, skew).distanceSquared, 1.0);
}

TEST(TriangleDistance, FarFromTheOriginAsAccurateAsNearIt) {
  const Vec3 o{1e6, 1e6, -2e6};
  const Triangle above{o + Vec3{0.1, 0.1, 0.5}, o + Vec3{0.3, 0.1, 0.5}, o + Vec3{0.1, 0.3, 0.5}};
  const Triangle base{o, o + Vec3{1, 0, 0}, o + Vec3{0, 1, 0}};
  EXPECT_DOUBLE_EQ(triangleDistanceBruteForce(base, above).distanceSquared, 0.25);
  EXPECT_DOUBLE_EQ(triangleDistanceBruteForce(above, base).distanceSquared, 0.25);
}

TEST(TriangleDistance, SliverPiercedThroughItsThinInterior) {
  // A needle of height 1e-10, turned out of the coordinate planes and pierced across its width:
  // distance 0, found only by the piercing test, and only with an accurate normal (a plain
  // cross product tilts this face by 1e-6 rad).
  const Quaternion turn = Quaternion::fromAxisAngle({0.3, -0.5, 0.8}, 0.7);
  auto place = [&](const Triangle& t) {
    return Triangle{turn.rotate(t.a), turn.rotate(t.b), turn.rotate(t.c)};
  };
  for (const double across : {0.25, 0.5, 0.75}) {
    const Triangle needle = place({{0, 0, 0}, {1, 0, 0}, {0.5, 1e-10, 0}});
    const Triangle pin = place({{0.5, across * 1e-10, -1}, {0.5, across * 1e-10, 1}, {3, 3, 3}});
    ASSERT_TRUE(exactIntersect(needle, pin));
    const auto r = triangleDistanceBruteForce(needle, pin);
    EXPECT_TRUE(r.intersect) << pasteable(needle, pin);
    EXPECT_TRUE(trianglesIntersect(needle, pin));
    EXPECT_TRUE(triangleDistanceBruteForce(pin, needle).intersect);
    // and a pin that stops 1e-9 short of the needle is 1e-9 away
    const Triangle shortPin =
        place({{0.5, across * 1e-10, -1}, {0.5, across * 1e-10, -1e-9}, {3, 3, -3}});
    const auto gap = triangleDistanceBruteForce(needle, shortPin);
    EXPECT_FALSE(gap.intersect);
    EXPECT_NEAR(distanceOf(gap), std::sqrt(exactSquaredDistance(needle, shortPin)), 1e-15);
    EXPECT_NEAR(distanceOf(gap), 1e-9, 1e-15);
  }
}

// ---------------------------------------------------------------------------------------------
// Against the exact oracle.

struct FamilyStats {
  double worstError = 0.0;    // max |d − d_exact| / size
  int flagDisagreements = 0;  // intersect ≠ exact do_intersect, exact distance < tolerance
  int intersecting = 0;
  int failures = 0;
};

/// Compares one pair with the exact oracle: distance, intersect flag, consistency with
/// trianglesIntersect, closest points on their triangles, barycentrics, and the intersection
/// point on both triangles. Prints the pair, pasteable, on failure.
void checkAgainstOracle(const Triangle& a, const Triangle& b, const char* family,
                        FamilyStats& stats) {
  const auto r = triangleDistanceBruteForce(a, b);
  const double size = pairSize(a, b);
  const double exact = std::sqrt(exactSquaredDistance(a, b));
  const bool exactFlag = exactIntersect(a, b);
  const double error = std::fabs(distanceOf(r) - exact) / size;
  stats.worstError = std::max(stats.worstError, error);
  stats.intersecting += exactFlag;
  std::string problem;
  if (!(std::isfinite(r.distanceSquared) && isFinite(r.p) && isFinite(r.q) && std::isfinite(r.a1) &&
        std::isfinite(r.a2) && std::isfinite(r.a3) && std::isfinite(r.a4)))
    problem += " not finite;";
  if (!(error <= kTolerance)) problem += " distance off by " + std::to_string(error) + " size;";
  if (exactFlag && !r.intersect) problem += " meets exactly but not intersecting;";
  if (r.intersect != exactFlag) {
    if (exact < kTolerance * size)
      ++stats.flagDisagreements;
    else
      problem += " intersect flag wrong;";
  }
  if (r.intersect != (r.distanceSquared == 0.0)) problem += " intersect but distance > 0;";
  if (trianglesIntersect(a, b) != r.intersect) problem += " trianglesIntersect disagrees;";
  const double slack = kTolerance * size + coordinateRounding(r);
  const double offA = std::sqrt(exactSquaredDistance(r.p, a));
  const double offB = std::sqrt(exactSquaredDistance(r.q, b));
  if (!(offA <= slack && offB <= slack)) problem += " p or q not on its triangle;";
  if (!(std::fabs(distance(r.p, r.q) - distanceOf(r)) <= slack)) problem += " |p - q| != d;";
  if (r.intersect && !(r.p == r.q)) problem += " intersecting but p != q;";
  const double barycentricSlack = 4 * kEpsilon;
  for (const auto& [u, v] : {std::pair{r.a1, r.a2}, std::pair{r.a3, r.a4}})
    if (!(u >= 0 && v >= 0 && u <= 1 && v <= 1 && u + v <= 1 + barycentricSlack))
      problem += " barycentrics outside the triangle;";
  // Barycentrics of a needle are ill-conditioned (ε·L/h): reconstruct only well-shaped triangles.
  auto wellShaped = [](const Triangle& t) {
    const double longest = std::max({distance(t.a, t.b), distance(t.b, t.c), distance(t.c, t.a)});
    return 2 * t.area() > 1e-3 * longest * longest;
  };
  if ((wellShaped(a) && !(distance(fromBarycentrics(a, r.a1, r.a2), r.p) <= slack)) ||
      (wellShaped(b) && !(distance(fromBarycentrics(b, r.a3, r.a4), r.q) <= slack)))
    problem += " barycentrics do not give p and q;";
  if (!problem.empty() && stats.failures++ < 3) {
    ADD_FAILURE() << family << ":" << problem << "\n d = " << distanceOf(r) << ", exact = " << exact
                  << ", intersect = " << r.intersect << ", exact intersect = " << exactFlag
                  << ", pair:\n"
                  << pasteable(a, b);
  }
}

void printStats(const char* what, const FamilyStats& s, std::size_t count) {
  std::printf(
      "[ stats    ] %-20s %8zu pairs: max |d - exact| / size = %.3g; %d intersect; %d touching "
      "within tolerance flagged differently from do_intersect\n",
      what, count, s.worstError, s.intersecting, s.flagDisagreements);
}

TEST(TriangleDistance, NeedlesAreNeitherPiercedBeyondTheirTipsNorMeasuredPastTheirShortEdges) {
  // An audit's cases. A segment crossing the plane of a needle (1e-12 high) just beyond its tip,
  // where the lines of its long edges lie within rounding of each other, pierced it: 3.9e-7 apart
  // called intersecting. And a point over a needle's face near its short edge (1e-7 long) was
  // taken for one off the face (one rounding bound for the three edges) and measured to a long
  // edge: 9.7e-9 for 1e-12.
  const Triangle needle{{0, 0, 0},
                        {0x1.1126ede545b65p-1, 0x1.adbb3a2487d22p-3, 0x1.a38303fb028e2p-1},
                        {0x1.1126ede5421c9p-2, 0x1.adbb3a2485caep-4, 0x1.a38303fb05079p-2}};
  const Triangle beyond{{0x1.13aca86a62b9p-1, 0x1.6b66fed8dfa5cp-1, 0x1.a68efbd567d6p-1},
                        {0x1.0ea1419dde068p-1, -0x1.2912b85972179p-2, 0x1.a07721ffc1f7p-1},
                        {0x1.1126f174b30bp+0, 0x1.adbb3fbe6a83p-2, 0x1.a3830972cbba4p+0}};
  const double apart = std::sqrt(test::exactSquaredDistance(needle, beyond));
  EXPECT_NEAR(apart, 3.8758393243535636e-07, 1e-20);
  EXPECT_FALSE(trianglesIntersect(needle, beyond));
  const auto r = triangleDistanceBruteForce(needle, beyond);
  EXPECT_FALSE(r.intersect);
  EXPECT_NEAR(std::sqrt(r.distanceSquared), apart, 1e-15);

  const Triangle shortEdged{{0, 0, 0}, {1, 0, 0}, {1, 0x1.ad7f29abcaf48p-24, 0}};
  const Vec3 q{0x1.ffffffaa19c47p-1, 0x1.ad7f29abcaf48p-25, 0x1.19799812dea11p-40};
  const Triangle above{q,
                       {0x1.3fffffd50ce24p+0, 0x1.000006b5fca6bp-3, 0x1.0000000001198p+0},
                       {0x1.7fffffaa19c47p-1, 0x1.0000035afe535p-2, 0x1.0000000001198p+0}};
  const double gap = std::sqrt(test::exactSquaredDistance(shortEdged, above));
  EXPECT_NEAR(gap, 1e-12, 1e-24);
  EXPECT_NEAR(std::sqrt(triangleDistanceBruteForce(shortEdged, above).distanceSquared), gap, 1e-16);

  // Turned needles and segments crossing their planes just beyond a tip: never intersecting
  // where the exact distance exceeds the touching tolerance (about 1.4e-14 here).
  test::PairRandom random(23);
  for (const double height : {1e-6, 1e-10, 1e-14}) {
    int found = 0;
    for (int i = 0; i < 200; ++i) {
      const Quaternion turn = Quaternion::fromAxisAngle(random.unitVector(), random.uniform(0, 3));
      const auto place = [&](const Vec3& v) { return turn.rotate(v); };
      const Triangle a{place({0, 0, 0}), place({1, 0, 0}), place({0.5, height, 0})};
      const Vec3 x{1 + std::pow(10.0, random.uniform(-9, -6)), 0, 0};
      const Vec3 direction =
          normalized(Vec3{random.uniform(-0.5, 0.5), random.uniform(-0.5, 0.5), 1});
      const Triangle b{place(x - direction * 0.5), place(x + direction * 0.5),
                       place(x + Vec3{1, 0, 0})};
      const double exact = std::sqrt(test::exactSquaredDistance(a, b));
      if (!(exact > 1e-13)) continue;
      ++found;
      ASSERT_FALSE(trianglesIntersect(a, b)) << height << "\n" << pasteable(a, b);
      ASSERT_NEAR(std::sqrt(triangleDistanceBruteForce(a, b).distanceSquared), exact, 1e-13)
          << pasteable(a, b);
    }
    EXPECT_GT(found, 150) << height;
  }
}

TEST(TriangleDistance, AVertexOverTheFaceWithinRoundingOfAnEdgeIsMeasuredToTheFace) {
  // A vertex whose projection lies within the rounded areas' rounding of an edge's line, just
  // over the face: its face candidate was dropped and the edges measured it, up to some 2⁸ε of
  // the size too far (here above the touching tolerance, 32ε of the size). The exact signs of
  // the point kernel's face test now decide it.
  test::PairRandom random(29);
  double worst = 0.0;
  for (std::size_t i = 0; i < test::scaledCount(4000); ++i) {
    const double offset = std::pow(10.0, random.uniform(0, 3));
    const Vec3 a = random.unitVector() * offset;
    const Triangle t{a, a + random.unitVector(), a + random.unitVector() * random.uniform(0.3, 1)};
    const Vec3 corner[3] = {t.a, t.b, t.c};
    const Vec3 start = corner[i % 3], edge = corner[(i + 1) % 3] - start;
    const Vec3 normal = normalized(t.areaVector());
    const Vec3 inward = normalized(cross(normal, edge));
    const double band = 600.0 * kEpsilon * (offset + 2.0);
    const Vec3 tip = start + edge * random.uniform(0.2, 0.8) + inward * (band * random.uniform()) +
                     normal * (band * std::pow(10.0, random.uniform(-3, 0)));
    // The other corners far above the face, leaning inward: the tip is the nearest feature.
    const Triangle above{tip, tip + (normal + inward * 0.5) * 0.5,
                         tip + (normal + inward * 0.5 + normalized(edge) * 0.3) * 0.5};
    const double exact = std::sqrt(test::exactSquaredDistance(t, above));
    const double error =
        std::fabs(std::sqrt(triangleDistanceBruteForce(t, above).distanceSquared) - exact) /
        (kEpsilon * (offset + 2.0));
    worst = std::max(worst, error);
    ASSERT_LE(error, 16.0) << pasteable(t, above);
  }
  std::printf("[ stats    ] vertex beside an edge: max |d - exact| = %.3g eps (size)\n", worst);
}

TEST(TriangleDistance, EdgesCrossingNearABoundaryWithinItsRoundingIntersect) {
  // An audit's pairs: an edge crossing the other triangle within the rounding of the inside
  // test, which measured them to the boundary they cross near: 9.4e-12 apart (L = 7.1, 1e3 from
  // the origin) and 4.5e-9 (L = 2048, 1e9 from it). The exact signs decide there.
  const Triangle near1000[2] = {
      {{0x1.c10a47b5f1e14p+9, -0x1.363fc35a3f9d2p+8, 0x1.388b042045473p+8},
       {0x1.c10a3ea128257p+9, -0x1.363fe2a68690fp+8, 0x1.388b7747b305dp+8},
       {0x1.c11d8bcf951adp+9, -0x1.35fd606a719eep+8, 0x1.3796cb6f06683p+8}},
      {{0x1.c12717a8e3dd3p+9, -0x1.35d8e4953061ep+8, 0x1.3707742c7c8c7p+8},
       {0x1.c0a8400f37d9cp+9, -0x1.37a10e56af979p+8, 0x1.3dc61e5e3b9aep+8},
       {0x1.c0e7abdc0ddbap+9, -0x1.36bcf975effd1p+8, 0x1.3a66c9455c13ap+8}}};
  const Triangle far[2] = {
      {{-0x1.b5e77b69da81fp+28, 0x1.ff13e9e5d3066p+28, -0x1.51d5eae688ffdp+29},
       {-0x1.b5e7a3931d39p+28, 0x1.ff13d8d711ed9p+28, -0x1.51d6024f80715p+29},
       {-0x1.b5e7cbbcda5bdp+28, 0x1.ff13c7c89e6c6p+28, -0x1.51d619b851835p+29}},
      {{-0x1.b5e7831e51e6ap+28, 0x1.ff13e696982dfp+28, -0x1.51d5ef6c4df9p+29},
       {-0x1.b5e761b82dba3p+28, 0x1.ff13f4b510a75p+28, -0x1.51d5dc02d409p+29},
       {-0x1.b5e7a48476131p+28, 0x1.ff13d8781fb48p+28, -0x1.51d602d5c7e8fp+29}}};
  for (const auto& pair : {near1000, far}) {
    for (const bool swapped : {false, true}) {
      const Triangle& a = pair[swapped ? 1 : 0];
      const Triangle& b = pair[swapped ? 0 : 1];
      ASSERT_TRUE(exactIntersect(a, b));
      EXPECT_TRUE(trianglesIntersect(a, b)) << pasteable(a, b);
      const auto r = triangleDistanceBruteForce(a, b);
      EXPECT_TRUE(r.intersect) << pasteable(a, b);
      EXPECT_EQ(r.distanceSquared, 0.0);
      const double slack = kTolerance * pairSize(a, b) + coordinateRounding(r);
      EXPECT_LE(std::sqrt(exactSquaredDistance(r.p, a)), slack);
      EXPECT_LE(std::sqrt(exactSquaredDistance(r.q, b)), slack);
    }
  }
}

/// Needles, 1e-14 to 1e-3 high, and triangles with an edge through a point within 1e-15 to 1e-6
/// of one of the needle's edges (inside or out), or lying nearly in its plane, turned, 0, 1e3 or
/// 1e9 from the origin. Where such a pair meets exactly, the rounded tests may find no witness.
std::pair<Triangle, Triangle> boundaryCrossingPair(test::PairRandom& random) {
  const double height = std::pow(10.0, random.uniform(-14, -3));
  const double apexAt[6] = {random.uniform(),
                            0.5,
                            std::pow(10.0, random.uniform(-14, -2)),
                            1 - std::pow(10.0, random.uniform(-14, -2)),
                            -std::pow(10.0, random.uniform(-3, 0)),
                            1 + std::pow(10.0, random.uniform(-3, 0))};
  const Triangle needle{{0, 0, 0}, {1, 0, 0}, {apexAt[random.below(6)], height, 0}};
  const Vec3 corners[3] = {needle.a, needle.b, needle.c};
  const int edge = random.below(3);
  const Vec3 from = corners[edge], to = corners[(edge + 1) % 3];
  const Vec3 outward =
      normalized(cross(to - from, Vec3{0, 0, 1})) *
      (dot(cross(to - from, Vec3{0, 0, 1}), needle.centroid() - from) > 0 ? -1 : 1);
  const double offset = (random.below(2) ? 1 : -1) * std::pow(10.0, random.uniform(-15, -6));
  const Vec3 point = from + (to - from) * random.uniform() + outward * offset;
  const double size = std::pow(10.0, random.uniform(-3, 0.5));
  Vec3 direction = random.unitVector();
  if (random.below(4) == 0)
    direction.z *= 1e-6;  // nearly in the needle's plane
  else if (std::fabs(direction.z) < 0.05)
    direction.z = std::copysign(0.05, direction.z);
  direction = normalized(direction);
  const double before = random.uniform();
  const Triangle other{point - direction * (before * size),
                       point + direction * ((1 - before) * size),
                       point + test::detail::orthogonal(direction) * size};
  const double offsets[3] = {0, 1e3, 1e9};
  const Vec3 shift = random.unitVector() * offsets[random.below(3)];
  return test::detail::rotated({needle, other}, random, shift);
}

TEST(TriangleIntersect, EveryPairThatMeetsExactlyIntersects) {
  // The rounded tests alone (edges piercing beyond the rounding of their signs, distances within
  // τ) missed 1 to 2 pairs in 1,000 of these that meet exactly.
  test::PairRandom random(37);
  const std::size_t count = test::scaledCount(20000);
  int meeting = 0, touchingApart = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const auto [a, b] = boundaryCrossingPair(random);
    const bool flag = trianglesIntersect(a, b);
    const auto r = triangleDistanceBruteForce(a, b);
    ASSERT_EQ(r.intersect, flag) << pasteable(a, b);
    if (exactIntersect(a, b)) {
      ++meeting;
      ASSERT_TRUE(flag) << "meets exactly, not found:\n" << pasteable(a, b);
      const double slack = kTolerance * pairSize(a, b) + coordinateRounding(r);
      ASSERT_LE(std::sqrt(exactSquaredDistance(r.p, a)), slack) << pasteable(a, b);
      ASSERT_LE(std::sqrt(exactSquaredDistance(r.q, b)), slack) << pasteable(a, b);
    } else if (flag) {
      ++touchingApart;  // within the touching tolerance τ (about 1e-14 of the coordinates)
      const double largest =
          std::max({maxAbs(a.a), maxAbs(a.b), maxAbs(a.c), maxAbs(b.a), maxAbs(b.b), maxAbs(b.c)});
      ASSERT_LE(std::sqrt(exactSquaredDistance(a, b)), 128 * kEpsilon * largest) << pasteable(a, b);
    } else {
      ASSERT_NEAR(distanceOf(r), std::sqrt(exactSquaredDistance(a, b)), kTolerance * pairSize(a, b))
          << pasteable(a, b);
    }
  }
  EXPECT_GT(meeting, static_cast<int>(count / 4));
  std::printf(
      "[ stats    ] %zu pairs near a needle's boundary: %d meet exactly, %d apart by less "
      "than the touching tolerance\n",
      count, meeting, touchingApart);
}

TEST(TriangleDistance, MatchesExactOracleOnEveryFamily) {
  const std::size_t count = test::scaledCount(3000);
  for (const PairFamily family : test::kAllFamilies) {
    FamilyStats stats;
    for (const auto& [a, b] : test::makePairs(family, count, 2024))
      checkAgainstOracle(a, b, name(family), stats);
    printStats(name(family), stats, count);
  }
}

/// The oracle itself: its interval filter against plain exact rationals, and its composition of
/// 15 candidates against CGAL's own triangle–triangle distance (non-degenerate pairs: both are
/// exact values rounded once, so they must be the same double).
TEST(TriangleDistance, ExactOracleAgreesWithRationalArithmeticAndCgal) {
  for (const PairFamily family : test::kAllFamilies) {
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(100), 555)) {
      const double rational = test::exactSquaredDistanceRational(a, b);
      const double filtered = exactSquaredDistance(a, b);
      const double d = std::sqrt(rational);
      EXPECT_LE(std::fabs(std::sqrt(filtered) - d),
                1.01 * test::kCertifiedFraction * (pairSize(a, b) + d))
          << name(family) << "\n"
          << pasteable(a, b);
      // and its point–triangle and segment–segment parts
      const double pointRational = test::exactSquaredDistanceRational(b.a, a);
      EXPECT_LE(std::fabs(std::sqrt(exactSquaredDistance(b.a, a)) - std::sqrt(pointRational)),
                1.01 * test::kCertifiedFraction * (pairSize(a, b) + std::sqrt(pointRational)));
      const double edgeRational = test::exactSquaredDistanceRational(a.a, a.b, b.b, b.c);
      EXPECT_LE(
          std::fabs(std::sqrt(exactSquaredDistance(a.a, a.b, b.b, b.c)) - std::sqrt(edgeRational)),
          1.01 * test::kCertifiedFraction * (pairSize(a, b) + std::sqrt(edgeRational)));
      const double thin = 1e-3 * pairSize(a, b) * pairSize(a, b);
      if (a.area() > thin && b.area() > thin) {
        EXPECT_EQ(rational, test::cgalTriangleSquaredDistance(a, b)) << name(family) << "\n"
                                                                     << pasteable(a, b);
      }
    }
  }
}

/// 10^5 random pairs in CI (5·10^4 Random + 5·10^4 NearContact). Set DELTA_LONG_ORACLE=N to run N
/// of each instead, e.g. DELTA_LONG_ORACLE=5000000 for 10^7 pairs (about 3 minutes).
TEST(TriangleDistance, RandomPairsMatchExactOracle) {
  std::size_t count = test::scaledCount(50000);
  if (const char* requested = std::getenv("DELTA_LONG_ORACLE"))
    count = static_cast<std::size_t>(std::strtoull(requested, nullptr, 10));
  constexpr std::size_t kBatch = 100000;  // generated in batches: 10^7 pairs need no 1 GB vector
  for (const PairFamily family : {PairFamily::Random, PairFamily::NearContact}) {
    FamilyStats stats;
    for (std::size_t done = 0, batch = 0; done < count; done += kBatch, ++batch) {
      for (const auto& [a, b] : test::makePairs(family, std::min(kBatch, count - done), 77 + batch))
        checkAgainstOracle(a, b, name(family), stats);
    }
    printStats(name(family), stats, count);
  }
}

// ---------------------------------------------------------------------------------------------
// Invariances.

/// Whether two results of the same pair (moved, reordered, swapped) agree: distances within the
/// tolerance; the intersect flags equal unless the pair touches within the tolerance.
void expectSameDistance(const TriangleDistanceResult& r, const TriangleDistanceResult& other,
                        const Triangle& a, const Triangle& b, double slack, int& failures) {
  const double size = pairSize(a, b);
  bool ok = std::fabs(distanceOf(r) - distanceOf(other)) <= kTolerance * size + slack;
  if (r.intersect != other.intersect)
    ok = ok && std::sqrt(exactSquaredDistance(a, b)) < kTolerance * size;
  if (!ok && failures++ < 3)
    ADD_FAILURE() << "d = " << distanceOf(r) << " vs " << distanceOf(other) << ", intersect "
                  << r.intersect << " vs " << other.intersect << " for\n"
                  << pasteable(a, b);
}

TEST(TriangleDistance, SymmetricInItsArguments) {
  for (const PairFamily family : test::kAllFamilies) {
    int failures = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(2000), 31)) {
      const auto r = triangleDistanceBruteForce(a, b);
      const auto swapped = triangleDistanceBruteForce(b, a);
      expectSameDistance(r, swapped, a, b, 0.0, failures);
      EXPECT_EQ(trianglesIntersect(b, a), swapped.intersect);
    }
  }
}

TEST(TriangleDistance, InvariantUnderVertexOrderAndOrientation) {
  for (const PairFamily family : test::kAllFamilies) {
    int failures = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(1000), 41)) {
      const auto r = triangleDistanceBruteForce(a, b);
      const Triangle rotatedA{a.b, a.c, a.a}, rotatedB{b.c, b.a, b.b};
      const Triangle flippedA{a.a, a.c, a.b}, flippedB{b.b, b.a, b.c};
      expectSameDistance(r, triangleDistanceBruteForce(rotatedA, b), a, b, 0.0, failures);
      expectSameDistance(r, triangleDistanceBruteForce(a, rotatedB), a, b, 0.0, failures);
      expectSameDistance(r, triangleDistanceBruteForce(flippedA, flippedB), a, b, 0.0, failures);
      expectSameDistance(r, triangleDistanceBruteForce(rotatedB, flippedA), a, b, 0.0, failures);
    }
  }
}

TEST(TriangleDistance, InvariantUnderRigidMotion) {
  test::PairRandom random(5);
  for (const PairFamily family : test::kAllFamilies) {
    int failures = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(1000), 43)) {
      const double size = pairSize(a, b);
      const Quaternion q = Quaternion::fromAxisAngle(random.unitVector(), random.uniform(0, 6.3));
      const Vec3 shift = random.inCube(10 * size);
      auto move = [&](const Triangle& t) {
        return Triangle{q.rotate(t.a) + shift, q.rotate(t.b) + shift, q.rotate(t.c) + shift};
      };
      const Triangle movedA = move(a), movedB = move(b);
      // The moved input is rounded: it is a different pair by up to ε·|coordinates|.
      const double inputRounding =
          8 * kEpsilon * std::max({maxAbs(movedA.a), maxAbs(movedB.a), maxAbs(a.a), maxAbs(b.a)});
      expectSameDistance(triangleDistanceBruteForce(a, b),
                         triangleDistanceBruteForce(movedA, movedB), a, b, inputRounding, failures);
    }
  }
}

TEST(TriangleDistance, NeverNaNOnDegenerateInput) {
  const Vec3 p{0.25, 0.5, 0.75};
  const Triangle cases[] = {
      {p, p, p},
      {p, p, p + Vec3{1e-300, 0, 0}},
      {p, p + Vec3{1, 0, 0}, p + Vec3{2, 0, 0}},
      {p, p + Vec3{1, 0, 0}, p + Vec3{1 + 1e-16, 0, 0}},
      {{0, 0, 0}, {1e-200, 0, 0}, {0, 1e-200, 0}},
      {{1e-6, 0, 0}, {0, 1e-6, 0}, {0, 0, 1e-6}},
  };
  for (const Triangle& a : cases) {
    for (const Triangle& b : cases) {
      const auto r = triangleDistanceBruteForce(a, b);
      EXPECT_TRUE(std::isfinite(r.distanceSquared) && isFinite(r.p) && isFinite(r.q) &&
                  std::isfinite(r.a1) && std::isfinite(r.a2) && std::isfinite(r.a3) &&
                  std::isfinite(r.a4))
          << pasteable(a, b);
      EXPECT_EQ(r.intersect, trianglesIntersect(a, b)) << pasteable(a, b);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// trianglesIntersect on its own.

TEST(TriangleIntersect, SeparatedPiercingTouchingAndCoplanar) {
  EXPECT_FALSE(trianglesIntersect(kUnit, {{0, 0, 1e-9}, {1, 0, 1e-9}, {0, 1, 1}}));
  EXPECT_TRUE(trianglesIntersect(kUnit, {{0, 0, 0}, {1, 0, 1e-9}, {0, 1, 1}}));        // vertex
  EXPECT_TRUE(trianglesIntersect(kUnit, {{0.3, 0.3, -1}, {0.3, 0.3, 1}, {2, 2, 2}}));  // pierce
  EXPECT_TRUE(trianglesIntersect(kUnit, {{0.9, 0.9, 0}, {0.9, -5, 0}, {5, 0.9, 0}}));  // coplanar
  EXPECT_FALSE(trianglesIntersect(kUnit, {{0.6, 0.6, 0}, {2, 0.6, 0}, {0.6, 2, 0}}));
  EXPECT_TRUE(trianglesIntersect(kUnit, {{0.5, 0.5, 0}, {2, 0.6, 0}, {0.6, 2, 0}}));  // on edge
  EXPECT_TRUE(trianglesIntersect(kUnit, kUnit));
}

TEST(TriangleIntersect, AgreesWithExactDoIntersect) {
  for (const PairFamily family : test::kAllFamilies) {
    int touching = 0, total = 0;
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(3000), 99)) {
      const bool flag = trianglesIntersect(a, b);
      const bool exactFlag = exactIntersect(a, b);
      ++total;
      if (flag == exactFlag) continue;
      const double exact = std::sqrt(exactSquaredDistance(a, b));
      if (flag && exact < kTolerance * pairSize(a, b)) {
        ++touching;  // apart by less than the touching tolerance: counted as touching
        continue;
      }
      ADD_FAILURE() << name(family) << ": trianglesIntersect = " << flag
                    << ", exact distance = " << exact << " for\n"
                    << pasteable(a, b);
      break;
    }
    std::printf(
        "[ stats    ] %-20s trianglesIntersect: %d of %d differ from do_intersect, all "
        "apart by less than 1e-12 of the size and counted as touching\n",
        name(family), touching, total);
  }
}

}  // namespace
}  // namespace delta::kernels
