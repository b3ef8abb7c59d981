#include "delta/kernels/sphere.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "delta/core/format.h"

#include "kernels/exact_distance.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

void expectNear(const Vec3& actual, const Vec3& expected, double tolerance) {
  EXPECT_NEAR(actual.x, expected.x, tolerance);
  EXPECT_NEAR(actual.y, expected.y, tolerance);
  EXPECT_NEAR(actual.z, expected.z, tolerance);
}

bool finite(const SphereContactResult& r) {
  return std::isfinite(r.gap) && isFinite(r.p) && isFinite(r.q) && isFinite(r.normal);
}

TEST(SphereContact, SeparatedSpheres) {
  const auto r = sphereSphere({{0, 0, 0}, 1}, {{3, 0, 0}, 1});
  EXPECT_DOUBLE_EQ(r.gap, 1.0);
  EXPECT_FALSE(r.overlap);
  EXPECT_EQ(r.normal, (Vec3{-1, 0, 0}));  // from the second toward the first
  EXPECT_EQ(r.p, (Vec3{1, 0, 0}));
  EXPECT_EQ(r.q, (Vec3{2, 0, 0}));
}

TEST(SphereContact, OverlappingSpheres) {
  const auto r = sphereSphere({{0, 0, 0}, 1}, {{0, 1.5, 0}, 1});
  EXPECT_DOUBLE_EQ(r.gap, -0.5);
  EXPECT_TRUE(r.overlap);
  EXPECT_EQ(r.normal, (Vec3{0, -1, 0}));
  EXPECT_EQ(r.p, (Vec3{0, 1, 0}));
  EXPECT_EQ(r.q, (Vec3{0, 0.5, 0}));
}

TEST(SphereContact, ConcentricSpheresGetPlusX) {
  const auto r = sphereSphere({{1, 2, 3}, 1}, {{1, 2, 3}, 2});
  EXPECT_DOUBLE_EQ(r.gap, -3.0);
  EXPECT_TRUE(r.overlap);
  EXPECT_EQ(r.normal, (Vec3{1, 0, 0}));
}

TEST(SphereContact, TinyAndHugeSeparationsStayFinite) {
  const auto tiny = sphereSphere({{1e-300, 0, 0}, 0}, {{0, 0, 0}, 0});
  EXPECT_TRUE(finite(tiny));
  EXPECT_EQ(tiny.normal, (Vec3{1, 0, 0}));
  EXPECT_GT(tiny.gap, 0.0);
  const auto huge = sphereSphere({{1e300, 1e300, 0}, 1}, {{-1e300, -1e300, 0}, 1});
  EXPECT_TRUE(finite(huge));
  EXPECT_NEAR(length(huge.normal), 1.0, 1e-15);
  const auto offset = sphereSphere({{1e6 + 0.5, 1e6, 1e6}, 0.25}, {{1e6, 1e6, 1e6}, 0.125});
  EXPECT_DOUBLE_EQ(offset.gap, 0.125);
}

const Triangle kUnit{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};

TEST(SphereContact, SphereAboveAndBelowTheFace) {
  const auto above = sphereTriangle({{0.25, 0.25, 2}, 0.5}, kUnit);
  EXPECT_DOUBLE_EQ(above.gap, 1.5);
  EXPECT_FALSE(above.overlap);
  expectNear(above.q, {0.25, 0.25, 0}, 1e-15);
  expectNear(above.normal, {0, 0, 1}, 1e-15);
  expectNear(above.p, {0.25, 0.25, 1.5}, 1e-15);
  const auto below = sphereTriangle({{0.25, 0.25, -2}, 0.5}, kUnit);
  expectNear(below.normal, {0, 0, -1}, 1e-15);
}

TEST(SphereContact, SphereNearAnEdgeAndAVertex) {
  const auto edge = sphereTriangle({{0.5, -1, 0}, 0.5}, kUnit);
  EXPECT_DOUBLE_EQ(edge.gap, 0.5);
  expectNear(edge.q, {0.5, 0, 0}, 1e-15);
  expectNear(edge.normal, {0, -1, 0}, 1e-15);
  const auto vertex = sphereTriangle({{-1, -1, 0}, 1}, kUnit);
  EXPECT_DOUBLE_EQ(vertex.gap, std::sqrt(2.0) - 1);
  expectNear(vertex.q, {0, 0, 0}, 1e-15);
  expectNear(vertex.normal, {-std::sqrt(0.5), -std::sqrt(0.5), 0}, 1e-15);
}

TEST(SphereContact, OverlappingTriangle) {
  const auto r = sphereTriangle({{0.25, 0.25, 0.1}, 0.5}, kUnit);
  EXPECT_DOUBLE_EQ(r.gap, -0.4);
  EXPECT_TRUE(r.overlap);
  expectNear(r.normal, {0, 0, 1}, 1e-15);
}

TEST(SphereContact, CentreOnTheTriangleGetsTheFaceNormal) {
  const auto r = sphereTriangle({{0.25, 0.25, 0}, 0.5}, kUnit);
  EXPECT_EQ(r.gap, -0.5);
  EXPECT_TRUE(r.overlap);
  expectNear(r.normal, {0, 0, 1}, 1e-15);
  const Triangle flipped{kUnit.a, kUnit.c, kUnit.b};
  expectNear(sphereTriangle({{0.25, 0.25, 0}, 0.5}, flipped).normal, {0, 0, -1}, 1e-15);
  const auto onEdge = sphereTriangle({{0.5, 0, 0}, 0.5}, kUnit);
  expectNear(onEdge.normal, {0, 0, 1}, 1e-15);
}

TEST(SphereContact, CentreOnTheFaceBesideAnEdgeGetsTheFaceNormal) {
  // An audit's cases: beside an edge the face's test defers to the edges within its rounding,
  // and a centre on the face 2⁻⁴⁶ from the edge got the edge's direction, in the face's plane.
  const auto on = sphereTriangle({{0x1p-1, 0x1p-46, 0}, 0x1p-2}, kUnit);
  expectNear(on.normal, {0, 0, 1}, 1e-15);
  EXPECT_NEAR(on.gap, -0.25, 1024 * std::numeric_limits<double>::epsilon());  // to its rounding
  expectNear(sphereTriangle({{0x1p-1, 0x1p-46, 0x1p-46}, 0x1p-2}, kUnit).normal, {0, 0, 1}, 1e-15);
  expectNear(sphereTriangle({{0x1p-1, 0x1p-46, 0x1p-44}, 0x1p-2}, kUnit).normal, {0, 0, 1}, 1e-15);
  // Every edge, on the face and just below it, 2⁻⁵⁰ to 2⁻⁴³ in from the edge.
  for (int exponent = -50; exponent <= -43; ++exponent) {
    const double in = std::ldexp(1.0, exponent);
    for (const Vec3& centre :
         {Vec3{0.25, in, 0}, Vec3{in, 0.5, 0}, Vec3{0.5 - in, 0.5 - in, 0}, Vec3{0.25, in, -in}}) {
      const auto r = sphereTriangle({centre, 0.1}, kUnit);
      EXPECT_NEAR(std::fabs(r.normal.z), 1.0, 1e-15) << exponent << " " << toString(centre);
    }
  }
}

TEST(SphereContact, ZeroAreaTriangles) {
  const Triangle segment{{0, 0, 0}, {2, 0, 0}, {1, 0, 0}};
  const auto on = sphereTriangle({{1, 0, 0}, 0.5}, segment);
  EXPECT_TRUE(finite(on));
  EXPECT_NEAR(length(on.normal), 1.0, 1e-15);
  EXPECT_NEAR(on.normal.x, 0.0, 1e-15);  // orthogonal to the segment
  const auto off = sphereTriangle({{1, 3, 0}, 0.5}, segment);
  EXPECT_DOUBLE_EQ(off.gap, 2.5);
  expectNear(off.normal, {0, 1, 0}, 1e-15);
  const Triangle point{{1, 1, 1}, {1, 1, 1}, {1, 1, 1}};
  const auto atPoint = sphereTriangle({{1, 1, 1}, 2}, point);
  EXPECT_EQ(atPoint.normal, (Vec3{1, 0, 0}));
  EXPECT_EQ(atPoint.gap, -2.0);
  const auto nearPoint = sphereTriangle({{1, 1, 4}, 2}, point);
  EXPECT_EQ(nearPoint.gap, 1.0);
  expectNear(nearPoint.normal, {0, 0, 1}, 1e-15);
}

/// Sphere–triangle gap is the point–triangle distance minus the radius, on every family
/// (centres at the other triangle's vertices), never NaN, and p lies on the sphere.
TEST(SphereContact, SphereTriangleMatchesExactDistanceOnEveryFamily) {
  for (const auto family : test::kAllFamilies) {
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(300), 13)) {
      const double size = test::pairSize(a, b);
      for (const Vec3& centre : {b.a, b.b, b.c}) {
        const Sphere sphere{centre, 0.1 * size};
        const auto r = sphereTriangle(sphere, a);
        ASSERT_TRUE(finite(r)) << test::pasteable(a, b);
        const double exact = std::sqrt(test::exactSquaredDistance(centre, a));
        const double rounding = 4 * std::numeric_limits<double>::epsilon() * maxAbs(centre);
        EXPECT_NEAR(r.gap, exact - sphere.radius, 1e-12 * size + rounding)
            << test::name(family) << "\n"
            << test::pasteable(a, b);
        EXPECT_NEAR(length(r.normal), 1.0, 1e-14);
        EXPECT_NEAR(distance(r.p, centre), sphere.radius, 1e-12 * size + rounding);
        EXPECT_EQ(r.overlap, r.gap < 0);
      }
    }
  }
}

/// Centres over the face (where the kernel takes the height along the unit normal) and beside
/// it, on both sides, at heights from 10⁻¹² to 10³ of the triangle's size, on triangles of every
/// size and offset: the gap within a few ulps of the exact distance, the normal the face's on
/// the centre's side (and the face's own where the centre is on the face), q on the triangle.
TEST(SphereContact, CentresOverTheFaceMatchTheExactDistance) {
  std::size_t checked = 0;
  for (const double size : {1e-9, 1.0, 1e6})
    for (const double offset : {0.0, 1.0, 1e6}) {
      const Vec3 o{offset, -offset, 0.5 * offset};
      const Triangle t{o, o + Vec3{size, 0.1 * size, 0}, o + Vec3{0.2 * size, size, 0.3 * size}};
      const Vec3 unitNormal = normalized(cross(t.b - t.a, t.c - t.a));
      for (const Vec3& barycentric :
           {Vec3{0.2, 0.3, 0.5}, Vec3{0.9, 0.05, 0.05}, Vec3{0.5, 0.5, 0.0}, Vec3{1.2, -0.1, -0.1}})
        for (const double height : {0.0, 1e-12, 1e-6, 0.3, 1e3})
          for (const double side : {1.0, -1.0}) {
            const Vec3 onPlane = t.a * barycentric.x + t.b * barycentric.y + t.c * barycentric.z;
            const Vec3 centre = onPlane + unitNormal * (side * height * size);
            const Sphere sphere{centre, 0.25 * size};
            const SphereContactResult r = sphereTriangle(sphere, t);
            ASSERT_TRUE(finite(r));
            const double exact = std::sqrt(test::exactSquaredDistance(centre, t));
            // The gap to a few ulps of |centre − a| (the kernel's frame), the points to a few of
            // their coordinates.
            const double eps = std::numeric_limits<double>::epsilon();
            const double local = 16 * eps * (maxAbs(centre - t.a) + size);
            EXPECT_NEAR(r.gap, exact - sphere.radius, local)
                << "size " << size << " offset " << offset << " height " << side * height;
            EXPECT_NEAR(length(r.normal), 1.0, 1e-15);
            EXPECT_NEAR(distance(r.p, centre), sphere.radius, local + 16 * eps * maxAbs(centre));
            EXPECT_NEAR(std::sqrt(test::exactSquaredDistance(r.q, t)), 0.0,
                        local + 16 * eps * maxAbs(t.a));
            // Over the face and clearly off it, the face's normal on the centre's side (where the
            // points round little against the triangle: at an offset of 10⁶ a 10⁻⁹ triangle's
            // points round by a tenth of its size, and the centre may fall beside it).
            const bool roundsLittle = 16 * eps * maxAbs(t.a) < 1e-3 * size;
            if (roundsLittle && barycentric.x > 0.0 && barycentric.y > 0.0 && barycentric.z > 0.0 &&
                exact > 1e3 * local) {
              const double above = dot(centre - t.a, unitNormal);
              expectNear(r.normal, above > 0.0 ? unitNormal : -unitNormal, 1e-14);
              ++checked;
            }
            if (roundsLittle && exact == 0.0 && barycentric.z > 0.1 && barycentric.y > 0.1)
              expectNear(r.normal, unitNormal, 1e-14);  // on the face: its own normal
          }
    }
  EXPECT_GT(checked, 50u);
}

bool sameBits(double x, double y) {
  return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y);
}

bool sameBits(const Vec3& x, const Vec3& y) {
  return sameBits(x.x, y.x) && sameBits(x.y, y.y) && sameBits(x.z, y.z);
}

/// A prepared triangle answers as the triangle itself, bit for bit, on every family (slivers,
/// needles, zero-area and point triangles, huge offsets): centres at the other triangle's
/// corners, on the triangle (its corners, edge midpoints, centroid: where the normal comes from
/// the face or the longest edge) and just off it.
TEST(SphereContact, PreparedTriangleGivesTheSameBitsOnEveryFamily) {
  std::size_t compared = 0;
  const auto expectSame = [&](const Sphere& sphere, const Triangle& t) {
    const SphereContactResult plain = sphereTriangle(sphere, t);
    const SphereContactResult prepared = sphereTriangle(sphere, PreparedTriangle(t));
    ++compared;
    return sameBits(plain.gap, prepared.gap) && sameBits(plain.p, prepared.p) &&
           sameBits(plain.q, prepared.q) && sameBits(plain.normal, prepared.normal) &&
           plain.overlap == prepared.overlap;
  };
  const Triangle special[] = {kUnit,
                              {{0, 0, 0}, {2, 0, 0}, {1, 0, 0}},            // a segment
                              {{1, 1, 1}, {1, 1, 1}, {1, 1, 1}},            // a point
                              {{0, -0.0, 0}, {-0.0, 1, 0}, {0, 0, -0.0}}};  // signed zeros
  for (const Triangle& t : special)
    for (const Vec3& centre : {t.a, t.b, t.c, (t.a + t.b) * 0.5, Vec3{0.25, 0.25, 0},
                               Vec3{-0.0, -0.0, -0.0}, Vec3{0.5, -1, 0}, Vec3{1, 1, 4}})
      EXPECT_TRUE(expectSame({centre, 0.5}, t)) << toString(centre);
  for (const auto family : test::kAllFamilies) {
    for (const auto& [a, b] : test::makePairs(family, test::scaledCount(300), 17)) {
      const double size = test::pairSize(a, b);
      const Vec3 centroid = (a.a + a.b + a.c) / 3.0;
      for (const Vec3& centre : {b.a, b.b, b.c, a.a, a.b, (a.b + a.c) * 0.5, centroid,
                                 centroid + (b.a - centroid) * 1e-9})
        ASSERT_TRUE(expectSame({centre, 0.1 * size}, a)) << test::name(family) << "\n"
                                                         << test::pasteable(a, b);
    }
  }
  EXPECT_GT(compared, 1000u);
}

}  // namespace
}  // namespace delta::kernels
