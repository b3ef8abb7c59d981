#include "delta/dem/narrow_phase.h"

#include <gtest/gtest.h>

#include <cmath>

#include "delta/mesh/primitives.h"
#include "delta/query/sphere_contacts.h"

namespace delta::dem {
namespace {

constexpr double kRadius = 0.01;
constexpr double kEpsilon = kRadius / 20.0;
constexpr double kFilter = kRadius / 4.0;

TEST(DemNarrowPhase, SphereSphereGapAndDepthFollowTheMeshConventions) {
  // Apart by 0.6ε: one point halfway between the surfaces, direction from the second centre.
  const Sphere first{{0, 0, 0}, kRadius}, second{{2 * kRadius + 0.6 * kEpsilon, 0, 0}, kRadius};
  const PairContacts apart = sphereSphereContacts(first, second, kEpsilon);
  ASSERT_EQ(apart.points.size(), 1u);
  const ContactPoint& point = apart.points[0];
  EXPECT_FALSE(point.overlap);
  EXPECT_NEAR(point.distance, 0.6 * kEpsilon, 1e-15);
  EXPECT_NEAR(distance(point.direction, {-1, 0, 0}), 0.0, 1e-15);
  EXPECT_NEAR(point.x.x, kRadius + 0.3 * kEpsilon, 1e-15);
  EXPECT_NEAR(distance(point.normal, point.direction * (0.5 * point.distance)), 0.0, 1e-15);
  // Overlapping by 0.5ε: the distance is the depth (the law's δ = 2ε + depth).
  const PairContacts overlapping =
      sphereSphereContacts(first, {{2 * kRadius - 0.5 * kEpsilon, 0, 0}, kRadius}, kEpsilon);
  ASSERT_EQ(overlapping.points.size(), 1u);
  EXPECT_TRUE(overlapping.points[0].overlap);
  EXPECT_NEAR(overlapping.points[0].distance, 0.5 * kEpsilon, 1e-15);
  // At 2ε and beyond: none (strictly closer than 2ε, as for meshes).
  EXPECT_TRUE(sphereSphereContacts(first, {{2 * kRadius + 2.5 * kEpsilon, 0, 0}, kRadius}, kEpsilon)
                  .points.empty());
}

TEST(DemNarrowPhase, AReusedResultGivesTheFreshResult) {
  // A World keeps one PairContacts a pair slot from step to step: what an earlier pair left in
  // it (points, a count) must not reach the next.
  const Sphere first{{0, 0, 0}, kRadius};
  const Sphere touching{{2 * kRadius + 0.6 * kEpsilon, 0, 0}, kRadius};
  const Sphere far{{2 * kRadius + 2.5 * kEpsilon, 0, 0}, kRadius};
  PairContacts reused;
  sphereSphereContacts(first, touching, kEpsilon, reused);
  ASSERT_EQ(reused.points.size(), 1u);
  EXPECT_EQ(reused.trianglePairs, 1u);
  sphereSphereContacts(first, far, kEpsilon, reused);
  EXPECT_TRUE(reused.points.empty());
  EXPECT_EQ(reused.trianglePairs, 0u);
  // A sphere over a floor's diagonal (two triangles found, one kept), then one far from it.
  QueryMesh floor(primitives::quad(0.1, 0.1));
  floor.transform({Quaternion::fromAxisAngle({0, 0, 1}, 0.3), {0.01, 0.0, 0.0}});
  const double offset = 0.3 * kRadius / std::sqrt(2.0);
  for (const Sphere& sphere : {Sphere{{offset, -offset, kRadius + 0.5 * kEpsilon}, kRadius},
                               Sphere{{0.0, 0.0, 2.0 * kRadius}, kRadius}}) {
    const PairContacts fresh = sphereMeshContacts(sphere, floor, kEpsilon, kFilter);
    const Sphere inFrame{floor.inversePose().apply(sphere.center), sphere.radius};
    const std::vector<ContactPoint> found =
        contactdetection::sphereContacts(std::span<const Sphere>(&inFrame, 1), floor, kEpsilon);
    finishSphereMeshContacts(found, floor, kFilter, reused);
    EXPECT_EQ(reused.trianglePairs, fresh.trianglePairs);
    ASSERT_EQ(reused.points.size(), fresh.points.size());
    for (std::size_t i = 0; i < fresh.points.size(); ++i) {
      EXPECT_EQ(reused.points[i].x, fresh.points[i].x);
      EXPECT_EQ(reused.points[i].direction, fresh.points[i].direction);
      EXPECT_EQ(reused.points[i].distance, fresh.points[i].distance);
    }
  }
  EXPECT_TRUE(reused.points.empty());
}

TEST(DemNarrowPhase, SphereAboveAFloorDiagonalIsPushedStraightUp) {
  // The quad's diagonal runs from (−s, −s) to (s, s); the centre is 0.3 r off it, over one
  // triangle. The other triangle's closest point is on the diagonal: no local minimum, dropped.
  const QueryMesh floor(primitives::quad(0.1, 0.1));
  const double offset = 0.3 * kRadius / std::sqrt(2.0);
  const Sphere sphere{{offset, -offset, kRadius + 0.5 * kEpsilon}, kRadius};
  const PairContacts found = sphereMeshContacts(sphere, floor, kEpsilon, kFilter);
  EXPECT_EQ(found.trianglePairs, 2u);
  ASSERT_EQ(found.points.size(), 1u);
  EXPECT_NEAR(distance(found.points[0].direction, {0, 0, 1}), 0.0, 1e-15);
  EXPECT_NEAR(found.points[0].distance, 0.5 * kEpsilon, 1e-15);
  EXPECT_EQ(found.points[0].first, 0u);
}

TEST(DemNarrowPhase, SphereMeshContactsMoveWithTheMeshAndTurnRound) {
  const Mesh grain = primitives::granulate(4, {kRadius, 0.8 * kRadius, 0.7 * kRadius});
  const QueryMesh still(grain);
  const Sphere sphere{{0.3 * kRadius, 0.2 * kRadius, 1.6 * kRadius}, kRadius};
  const PairContacts here = sphereMeshContacts(sphere, still, kEpsilon, kFilter);
  // Move both by a rigid motion: the same points, moved.
  const RigidTransform motion{Quaternion::fromAxisAngle({1, 2, 3}, 0.9), {1.0, -2.0, 0.5}};
  QueryMesh moved = still;
  moved.transform(motion);
  const PairContacts there =
      sphereMeshContacts({motion.apply(sphere.center), kRadius}, moved, kEpsilon, kFilter);
  const PairContacts turned =
      meshSphereContacts(moved, {motion.apply(sphere.center), kRadius}, kEpsilon, kFilter);
  ASSERT_EQ(here.points.size(), there.points.size());
  ASSERT_EQ(turned.points.size(), there.points.size());
  if (here.points.empty()) GTEST_SKIP() << "no contact at this placement";
  for (std::size_t i = 0; i < here.points.size(); ++i) {
    EXPECT_NEAR(distance(motion.apply(here.points[i].x), there.points[i].x), 0.0, 1e-14);
    EXPECT_NEAR(
        distance(motion.rotation.rotate(here.points[i].direction), there.points[i].direction), 0.0,
        1e-12);
    EXPECT_NEAR(here.points[i].distance, there.points[i].distance, 1e-14);
    EXPECT_EQ(turned.points[i].direction, -there.points[i].direction);
    EXPECT_EQ(turned.points[i].first, there.points[i].second);
  }
}

}  // namespace
}  // namespace delta::dem
