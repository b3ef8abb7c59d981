// How far a pair of prepared meshes has moved against each other (query/detail/dual_traversal.h's
// relativeMove), the bound the contact and overlap caches keep their pairs by: no distance
// between a vertex of one and a vertex of the other changes by more, at random pose changes of
// random pairs (both meshes moved, large turns and small); and it is the small body's move that
// counts, not a large obstacle's swung round in the small body's frame.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "query/detail/dual_traversal.h"
#include "query/detail/query_mesh_data.h"

namespace delta::detail {
namespace {

RigidTransform randomPose(std::mt19937_64& random, double turn, double shift) {
  std::normal_distribution<double> normal;
  const Vec3 axis{normal(random), normal(random), normal(random)};
  return {Quaternion::fromAxisAngle(axis, turn * normal(random)),
          Vec3{normal(random), normal(random), normal(random)} * shift};
}

/// The largest change, between two placements of the second mesh in the first's frame, of a
/// distance from a vertex of the first to a vertex of the second.
double largestChange(const QueryMeshData& first, const QueryMeshData& second,
                     const MatrixMotion& then, const MatrixMotion& now) {
  double largest = 0.0;
  for (const Vec3& a : first.vertices)
    for (const Vec3& b : second.vertices)
      largest = std::max(largest, std::abs(length(a - now.apply(b)) - length(a - then.apply(b))));
  return largest;
}

TEST(RelativeMove, BoundsEveryChangeOfADistance) {
  std::mt19937_64 random(3);
  const QueryMesh small(primitives::granulate(2)), large(primitives::box({40, 40, 2}));
  const QueryMesh pairs[][2] = {{small, large}, {large, small}, {small, small}};
  for (const auto& pair : pairs)
    for (const double turn : {1e-4, 1e-2, 0.5})
      for (int trial = 0; trial < 20; ++trial) {
        QueryMesh first = pair[0], second = pair[1];
        first.setPose(randomPose(random, 1.0, 3.0));
        second.setPose(randomPose(random, 1.0, 3.0));
        const MatrixMotion then = matrixMotion(first.inversePose() * second.pose());
        first.setPose(randomPose(random, turn, turn) * first.pose());
        second.setPose(randomPose(random, turn, turn) * second.pose());
        const MatrixMotion now = matrixMotion(first.inversePose() * second.pose());
        const double move =
            relativeMove(first.data(), second.data(), now, then.rotation, then.translation);
        const double change = largestChange(first.data(), second.data(), then, now);
        EXPECT_LE(change, move * (1.0 + 1e-12) + 1e-13) << "turn " << turn << ", trial " << trial;
        EXPECT_GT(move, 0.0);
      }
}

TEST(RelativeMove, ASmallBodyTurningByALargeOneMovesByItsOwnSize) {
  // A granulate (radius about 1) turned by θ about its centre next to a 400-unit floor: in its
  // own frame the floor's corners swing round by 280·θ; in the floor's, the granulate's points
  // move by at most its radius times θ.
  const QueryMesh floorMesh(primitives::box({400, 400, 2}, {0, 0, -2}));
  QueryMesh particle(primitives::granulate(2));
  const MatrixMotion then = matrixMotion(particle.inversePose() * floorMesh.pose());
  const double theta = 1e-3;
  particle.setPose(RigidTransform{Quaternion::fromAxisAngle({1, 1, 0}, theta), {}});
  const MatrixMotion now = matrixMotion(particle.inversePose() * floorMesh.pose());
  const double move =
      relativeMove(particle.data(), floorMesh.data(), now, then.rotation, then.translation);
  const double radius = particle.data().radius + length(particle.data().bounds.center());
  EXPECT_LE(move, 1.01 * radius * theta + 1e-12);
  EXPECT_GE(move, largestChange(particle.data(), floorMesh.data(), then, now));
  // The other way round (the floor first, the particle moving in its frame) too.
  const MatrixMotion floorThen = matrixMotion(floorMesh.inversePose() * RigidTransform{});
  const MatrixMotion floorNow = matrixMotion(floorMesh.inversePose() * particle.pose());
  EXPECT_LE(relativeMove(floorMesh.data(), particle.data(), floorNow, floorThen.rotation,
                         floorThen.translation),
            1.01 * radius * theta + 1e-12);
}

}  // namespace
}  // namespace delta::detail
