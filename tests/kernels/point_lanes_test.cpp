// The point queries' leaf bounds (kernels/detail/point_lanes.h): for every ISA, a lower bound
// never above and an upper bound never below the exact kernel's squared distance (which decides
// every answer), on every adversarial triangle family, and both close to it for well-shaped
// triangles (a lower bound of 0 or an upper bound of +∞ everywhere would be correct and useless:
// the tightness checks catch it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/triangle_soa.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/query_mesh_data.h"

namespace delta::kernels {
namespace {

/// Eight triangles and a point; the bounds of every supported ISA against the exact kernel.
struct Checked {
  int below = 0;   ///< lower bounds that were ≤ the exact squared distance (all must be)
  int above = 0;   ///< upper bounds that were ≥ it (all must be)
  int tight = 0;   ///< well-shaped lanes whose two bounds are within 1e-6 of it
  int shaped = 0;  ///< well-shaped lanes
  int boxed = 0;   ///< calls that stopped at the boxes (all eight beyond the pruning bound)
};

/// sin² of the angle at a ≥ 2⁻¹⁸: comfortably above the kernel's 2⁻²⁰ sliver cut.
bool wellShaped(const Triangle& t) {
  const Vec3 u = t.b - t.a, v = t.c - t.a;
  return lengthSquared(cross(u, v)) > 0x1p-18 * lengthSquared(u) * lengthSquared(v);
}

/// The eight triangles as the point queries' leaves hold them: in single precision, less the
/// centre of their box.
detail::FloatTriangles lanesOf(const std::vector<Triangle>& eight) {
  Aabb box;
  for (const Triangle& t : eight)
    box.extend(t.bounds());
  return detail::floatTriangles(
      eight.size(), [&eight](std::size_t k) { return eight[k]; }, box.center());
}

/// Whether the bounds were made (false: the boxes put all eight beyond `prune`).
bool boundsOf(Isa isa, const detail::FloatTriangles& lanes, const Vec3& p, double (&lower)[8],
              double (&upper)[8], double prune = INFINITY) {
  const Vec3 local = p - lanes.origin;
  return detail::batchKernels(isa).pointTriangleBounds(lanes.view(), 0, {local.x, local.y, local.z},
                                                       prune, lower, upper);
}

void check(Isa isa, const std::vector<Triangle>& eight, const Vec3& p, Checked& checked,
           const char* family) {
  const detail::FloatTriangles lanes = lanesOf(eight);
  double bounds[8], upper[8];
  ASSERT_TRUE(boundsOf(isa, lanes, p, bounds, upper));
  // A pruning bound below every distance may stop at the triangles' boxes; one at the nearest
  // distance or above must not.
  double nearest = INFINITY;
  for (const Triangle& t : eight)
    nearest = std::min(nearest, closestPointOnTriangle(p, t).distanceSquared);
  double unused[8], unusedToo[8];
  for (const double prune : {0.0, 0.5 * nearest, 0.999 * nearest})
    checked.boxed += !boundsOf(isa, lanes, p, unused, unusedToo, prune);
  ASSERT_TRUE(boundsOf(isa, lanes, p, unused, unusedToo, nearest)) << name(isa) << ", " << family;
  for (std::size_t i = 0; i < eight.size(); ++i) {
    const double exact = closestPointOnTriangle(p, eight[i]).distanceSquared;
    // NaN is allowed (nothing known) but must not occur for these finite, moderate inputs.
    ASSERT_FALSE(std::isnan(bounds[i])) << name(isa) << ", " << family;
    ASSERT_FALSE(std::isnan(upper[i])) << name(isa) << ", " << family;
    ASSERT_LE(bounds[i], exact) << name(isa) << ", " << family << ", lane " << i << ": p = (" << p.x
                                << ", " << p.y << ", " << p.z << ")";
    ASSERT_GE(upper[i], exact) << name(isa) << ", " << family << ", lane " << i << ": p = (" << p.x
                               << ", " << p.y << ", " << p.z << ")";
    ++checked.below;
    ++checked.above;
    if (wellShaped(eight[i])) {
      ++checked.shaped;
      const Vec3 a = eight[i].a;
      const double size = std::max({distance(a, eight[i].b), distance(a, eight[i].c),
                                    distance(eight[i].b, eight[i].c), distance(p, a)});
      // The margin's share, and the single-precision vertices' (δ in the distance).
      const double tolerance =
          1e-6 * size * (size + std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)})) +
          10.0 * size * lanes.rounding + 2.0 * lanes.rounding * lanes.rounding;
      if (bounds[i] >= exact - tolerance && upper[i] <= exact + tolerance) ++checked.tight;
    }
  }
}

TEST(PointLanes, BoundsNeverExceedTheExactKernelOnEveryFamily) {
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (const auto family : test::kAllFamilies) {
      test::PairRandom random(23);
      const auto pairs = test::makePairs(family, test::scaledCount(800), 5);
      for (std::size_t first = 0; first + 8 <= pairs.size(); first += 8) {
        std::vector<Triangle> eight;
        for (std::size_t i = first; i < first + 8; ++i)
          eight.push_back(pairs[i].first);
        const double size = test::pairSize(pairs[first].first, pairs[first].second);
        // Vertices, the other triangle's vertices (touching, coplanar), points near and far.
        const Vec3 queries[] = {eight[0].a,
                                (eight[1].b + eight[1].c) * 0.5,
                                eight[2].centroid(),
                                pairs[first].second.a,
                                pairs[first].second.centroid(),
                                eight[3].centroid() + random.inCube(size),
                                eight[4].a + random.inCube(0.01 * size),
                                eight[5].b + random.inCube(30 * size)};
        for (const Vec3& p : queries)
          check(isa, eight, p, checked, test::name(family));
      }
    }
    std::printf(
        "[ stats    ] %-6s %d lanes checked, %d of %d well-shaped lanes tight, %d calls "
        "stopped at the boxes\n",
        name(isa), checked.below, checked.tight, checked.shaped, checked.boxed);
    EXPECT_GT(checked.shaped, 1000);
    EXPECT_GT(checked.boxed, 1000);
    EXPECT_EQ(checked.tight, checked.shaped) << name(isa);
  }
}

TEST(PointLanes, SliversAndZeroAreaAreBoundedByTheirBoxes) {
  // A needle: its angle at a is far below the cut, so its lower bound must be its box's (the
  // plain normal's direction is off by ε/sin α there, and the face distance with it).
  const Triangle needle{{0, 0, 0}, {1, 0, 0}, {1, 1e-12, 0}};
  const Triangle point{{2, 2, 2}, {2, 2, 2}, {2, 2, 2}};
  const Triangle segment{{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  const Triangle fine{{0, 0, 5}, {1, 0, 5}, {0, 1, 5}};
  const std::vector<Triangle> eight{needle, point, segment, fine, needle, point, segment, fine};
  const Vec3 p{0.5, 0.3, 0.7};
  for (Isa isa : supportedIsas()) {
    Checked checked;
    check(isa, eight, p, checked, "degenerate");
    double bounds[8], upper[8];
    ASSERT_TRUE(boundsOf(isa, lanesOf(eight), p, bounds, upper)) << name(isa);
    for (int i : {0, 1, 2, 4, 5, 6}) {
      const Aabb box = eight[static_cast<std::size_t>(i)].bounds();
      const Vec3 gap = max(max(box.lower - p, p - box.upper), Vec3{0, 0, 0});
      EXPECT_LE(bounds[i], lengthSquared(gap)) << name(isa) << ", lane " << i;
      EXPECT_GE(bounds[i], 0.99 * lengthSquared(gap)) << name(isa) << ", lane " << i;
      // The nearest edge's distance, which is the triangle's for these (no face to be nearer).
      const double exact = closestPointOnTriangle(p, eight[i]).distanceSquared;
      EXPECT_GE(upper[i], exact) << name(isa) << ", lane " << i;
      EXPECT_LE(upper[i], exact + 1e-5) << name(isa) << ", lane " << i;  // the margin
    }
    EXPECT_GT(bounds[3], 0.9 * closestPointOnTriangle(p, fine).distanceSquared) << name(isa);
    EXPECT_LT(upper[3], 1.1 * closestPointOnTriangle(p, fine).distanceSquared) << name(isa);
  }
}

TEST(PointLanes, BoundsNeverExceedTheExactKernelFarFromTheOrigin) {
  // Every family moved 1e8, 1e12 and 2¹⁵⁰ from the origin (the lanes' origin is the eight's box
  // centre, so their floats stay fine): the exact kernel's differences round by ε of the
  // differences, not of the offset, and the margin's share of the offset (2⁻³⁶) stays far above
  // it.
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (const double offset : {1e8, 1e12, 0x1p150})
      for (const auto family : test::kAllFamilies) {
        test::PairRandom random(29);
        const auto pairs = test::makePairs(family, test::scaledCount(200), 5);
        const Vec3 shift{offset, -0.5 * offset, 0.25 * offset};
        const auto moved = [&shift](const Triangle& t) {
          return Triangle{t.a + shift, t.b + shift, t.c + shift};
        };
        for (std::size_t first = 0; first + 8 <= pairs.size(); first += 8) {
          std::vector<Triangle> eight;
          for (std::size_t i = first; i < first + 8; ++i)
            eight.push_back(moved(pairs[i].first));
          const double size = test::pairSize(pairs[first].first, pairs[first].second);
          const Vec3 queries[] = {eight[0].a,
                                  (eight[1].b + eight[1].c) * 0.5,
                                  eight[2].centroid(),
                                  moved(pairs[first].second).a,
                                  eight[3].centroid() + random.inCube(size),
                                  eight[4].a + random.inCube(0.01 * size),
                                  eight[5].b + random.inCube(30 * size)};
          for (const Vec3& p : queries)
            check(isa, eight, p, checked, test::name(family));
        }
      }
    EXPECT_GT(checked.below, 1000) << name(isa);
  }
}

TEST(PointLanes, SinglePrecisionVerticesWidenTheBounds) {
  // Eight triangles spread over 10³ about the origin of their lanes, with vertices that are no
  // floats (a float there is off by up to 3·10⁻⁵), and points 0.1 to 3 from one of them: the
  // float triangles' squared distances are off by up to 2·d·δ, several times the margin, and only
  // the widening by δ keeps the bounds on their sides. (With δ = 0 this fails.)
  test::PairRandom random(59);
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (int round = 0; round < 300; ++round) {
      std::vector<Triangle> eight;
      for (int i = 0; i < 8; ++i) {
        const Vec3 a = random.inCube(1e3);
        eight.push_back({a, a + random.inCube(2.0), a + random.inCube(2.0)});
      }
      const Triangle& t = eight[static_cast<std::size_t>(round % 8)];
      const Vec3 normal = normalized(cross(t.b - t.a, t.c - t.a));
      const Vec3 on = t.a + (t.b - t.a) * 0.3 + (t.c - t.a) * 0.2;
      for (const Vec3& p : {on + normal * 0.1, on - normal * 3.0, t.b + random.inCube(1.0), on})
        check(isa, eight, p, checked, "beside single-precision vertices");
    }
    EXPECT_EQ(checked.below, 300 * 4 * 8);
  }
}

TEST(PointLanes, NaNOrNothingBeyondSinglePrecision) {
  // Triangles 10³⁹ from the origin of their lanes: no float holds them, δ is infinite, and no
  // lower bound may exceed 0 nor any upper bound be finite.
  const std::vector<Triangle> eight(8, Triangle{{-1e39, 0, 0}, {1e39, 1, 0}, {0, 1e39, 1}});
  for (Isa isa : supportedIsas()) {
    const detail::FloatTriangles lanes = lanesOf(eight);
    EXPECT_TRUE(std::isinf(lanes.rounding));
    double bounds[8], upper[8];
    ASSERT_TRUE(boundsOf(isa, lanes, {0.5, 0.25, 3.0}, bounds, upper)) << name(isa);
    for (int i = 0; i < 8; ++i) {
      EXPECT_FALSE(bounds[i] > 0.0) << name(isa) << ", lane " << i;
      EXPECT_FALSE(upper[i] < INFINITY) << name(isa) << ", lane " << i;
    }
  }
}

TEST(PointLanes, NeedlesInAnyDirectionStayBelow) {
  // Needles with an angle of about 1e-11 at a, turned in random directions so that their plain
  // normals carry rounding of ε/sin α ≈ 2e-5 in direction, and points above their faces: a
  // bound from that normal would be off by far more than any margin, which is why such lanes
  // get only their boxes' bound.
  test::PairRandom random(41);
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (int round = 0; round < 200; ++round) {
      std::vector<Triangle> eight;
      for (int i = 0; i < 8; ++i) {
        const Vec3 a = random.inCube(1.0), along = random.unitVector();
        const Vec3 across = normalized(cross(along, random.unitVector()));
        eight.push_back({a, a + along, a + along * 0.999 + across * 1e-11});
      }
      const Triangle& t = eight[static_cast<std::size_t>(round % 8)];
      const Vec3 normal = normalized(cross(t.b - t.a, t.c - t.a));
      check(isa, eight, t.a + (t.b - t.a) * 0.9 + normal * 0.5, checked, "needles");
    }
    EXPECT_EQ(checked.below, 1600);
    EXPECT_EQ(checked.above, 1600);
  }
}

TEST(PointLanes, FarFromTheOriginASmallTriangleIsBracketed) {
  // A small triangle at 1e6 and a point 1e-3 above it: the bounds stay on their sides of the
  // exact distance for every ISA (and for a point exactly on the triangle, lower at most 0).
  const Vec3 at{1e6, -2e6, 3e6};
  const Triangle t{at, at + Vec3{1e-3, 0, 0}, at + Vec3{0, 1e-3, 0}};
  const std::vector<Triangle> eight(8, t);
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (const Vec3& p : {t.centroid() + Vec3{0, 0, 1e-3}, t.centroid(), t.a, t.b + Vec3{1, 1, 1}})
      check(isa, eight, p, checked, "far");
    EXPECT_EQ(checked.below, 32);
    EXPECT_EQ(checked.above, 32);
  }
}

}  // namespace
}  // namespace delta::kernels
