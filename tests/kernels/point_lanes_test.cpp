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

namespace delta::kernels {
namespace {

/// Eight triangles and a point; the bounds of every supported ISA against the exact kernel.
struct Checked {
  int below = 0;   ///< lower bounds that were ≤ the exact squared distance (all must be)
  int above = 0;   ///< upper bounds that were ≥ it (all must be)
  int tight = 0;   ///< well-shaped lanes whose two bounds are within 1e-6 of it
  int shaped = 0;  ///< well-shaped lanes
};

/// sin² of the angle at a ≥ 2⁻¹⁸: comfortably above the kernel's 2⁻²⁰ sliver cut.
bool wellShaped(const Triangle& t) {
  const Vec3 u = t.b - t.a, v = t.c - t.a;
  return lengthSquared(cross(u, v)) > 0x1p-18 * lengthSquared(u) * lengthSquared(v);
}

void check(Isa isa, const std::vector<Triangle>& eight, const Vec3& p, Checked& checked,
           const char* family) {
  TriangleSoA soa;
  soa.assign(eight);
  const detail::SoaView view = detail::soaView(soa);
  double bounds[8], upper[8];
  detail::batchKernels(isa).pointTriangleBounds(view, 0, {p.x, p.y, p.z}, bounds, upper);
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
      const double scale =
          size * (size + std::max({std::fabs(a.x), std::fabs(a.y), std::fabs(a.z)}));
      if (bounds[i] >= exact - 1e-6 * scale && upper[i] <= exact + 1e-6 * scale) ++checked.tight;
    }
  }
}

TEST(PointLanes, BoundsNeverExceedTheExactKernelOnEveryFamily) {
  for (Isa isa : supportedIsas()) {
    Checked checked;
    for (const auto family : testing::kAllFamilies) {
      testing::PairRandom random(23);
      const auto pairs = testing::makePairs(family, testing::scaledCount(800), 5);
      for (std::size_t first = 0; first + 8 <= pairs.size(); first += 8) {
        std::vector<Triangle> eight;
        for (std::size_t i = first; i < first + 8; ++i)
          eight.push_back(pairs[i].first);
        const double size = testing::pairSize(pairs[first].first, pairs[first].second);
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
          check(isa, eight, p, checked, testing::name(family));
      }
    }
    std::printf("[ stats    ] %-6s %d lanes checked, %d of %d well-shaped lanes tight\n", name(isa),
                checked.below, checked.tight, checked.shaped);
    EXPECT_GT(checked.shaped, 1000);
    EXPECT_EQ(checked.tight, checked.shaped) << name(isa);
  }
}

TEST(PointLanes, SliversAndZeroAreaGetNoBound) {
  // A needle: its angle at a is far below the cut, so the bound must be 0 (the plain normal's
  // direction is off by ε/sin α there, and the face distance with it).
  const Triangle needle{{0, 0, 0}, {1, 0, 0}, {1, 1e-12, 0}};
  const Triangle point{{2, 2, 2}, {2, 2, 2}, {2, 2, 2}};
  const Triangle segment{{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  const Triangle fine{{0, 0, 5}, {1, 0, 5}, {0, 1, 5}};
  const std::vector<Triangle> eight{needle, point, segment, fine, needle, point, segment, fine};
  const Vec3 p{0.5, 0.3, 0.7};
  for (Isa isa : supportedIsas()) {
    Checked checked;
    check(isa, eight, p, checked, "degenerate");
    TriangleSoA soa;
    soa.assign(eight);
    double bounds[8], upper[8];
    detail::batchKernels(isa).pointTriangleBounds(detail::soaView(soa), 0, {p.x, p.y, p.z}, bounds,
                                                  upper);
    for (int i : {0, 1, 2, 4, 5, 6}) {
      EXPECT_EQ(bounds[i], 0.0) << name(isa) << ", lane " << i;
      // The nearest edge's distance, which is the triangle's for these (no face to be nearer).
      const double exact = closestPointOnTriangle(p, eight[i]).distanceSquared;
      EXPECT_GE(upper[i], exact) << name(isa) << ", lane " << i;
      EXPECT_LE(upper[i], exact + 1e-5) << name(isa) << ", lane " << i;  // the margin
    }
    EXPECT_GT(bounds[3], 0.9 * closestPointOnTriangle(p, fine).distanceSquared) << name(isa);
    EXPECT_LT(upper[3], 1.1 * closestPointOnTriangle(p, fine).distanceSquared) << name(isa);
  }
}

TEST(PointLanes, NeedlesInAnyDirectionStayBelow) {
  // Needles with an angle of about 1e-11 at a, turned in random directions so that their plain
  // normals carry rounding of ε/sin α ≈ 2e-5 in direction, and points above their faces: a
  // bound from that normal would be off by far more than any margin, which is why such lanes
  // get 0.
  testing::PairRandom random(41);
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

TEST(PointLanes, FarFromTheOriginTheMarginGrowsWithTheCoordinates) {
  // A small triangle at 1e6 and a point 1e-3 above it: the local differences carry rounding of
  // ε·1e6, so the bounds must stand off the exact distance by at least that much, yet stay on
  // their sides of it for every ISA (and for a point exactly on the triangle, lower at most 0).
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
