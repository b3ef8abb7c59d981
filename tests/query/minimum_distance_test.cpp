#include "delta/query/minimum_distance.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/primitives.h"

namespace delta::contactdetection {
namespace {

/// Every pair by the scalar brute force: the reference.
MinimumDistance byAllPairs(const Mesh& first, const Mesh& second) {
  MinimumDistance best;
  best.distance = INFINITY;
  for (std::uint32_t i = 0; i < first.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < second.triangleCount(); ++j) {
      const auto r = kernels::triangleDistanceBruteForce(first.triangle(i), second.triangle(j));
      if (std::sqrt(r.distanceSquared) < best.distance)
        best = {std::sqrt(r.distanceSquared), i, j, r.p, r.q, r.intersect};
    }
  return best;
}

struct Scene {
  Mesh first, second;
};

std::vector<Scene> scenes() {
  std::vector<Scene> all;
  // Two granulates a small gap apart, the second turned.
  Mesh a = primitives::granulate(1);
  Mesh b = primitives::granulate(2);
  b.rotate({1, 2, 3}, 0.7).translate({2.05, 0.1, -0.2});
  all.push_back({a, b});
  // Interpenetrating: distance 0, intersect.
  Mesh c = primitives::icosphere(2);
  Mesh d = primitives::box({1, 1, 1}, {0.9, 0, 0});
  all.push_back({c, d});
  // Far apart and far from the origin.
  Mesh e = primitives::cylinder(1, 2, 12, {1e6, 1e6, 0});
  Mesh f = primitives::icosphere(1, 0.5, {1e6 + 7, 1e6 + 1, 3});
  all.push_back({e, f});
  return all;
}

TEST(MinimumDistance, MatchesAllPairsByBruteForce) {
  for (const Scene& scene : scenes()) {
    const MinimumDistance expected = byAllPairs(scene.first, scene.second);
    const double size = scene.first.bounds().diagonal() + scene.second.bounds().diagonal();
    for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
      const MinimumDistance actual =
          minimumDistance(flatten(scene.first), flatten(scene.second), solver);
      EXPECT_NEAR(actual.distance, expected.distance, 1e-12 * size) << kernels::name(solver);
      EXPECT_EQ(actual.intersect, expected.intersect);
      // the pair found attains the minimum (several pairs may tie)
      const auto check = kernels::triangleDistanceBruteForce(scene.first.triangle(actual.first),
                                                             scene.second.triangle(actual.second));
      EXPECT_NEAR(std::sqrt(check.distanceSquared), expected.distance, 1e-12 * size);
      EXPECT_NEAR(distance(actual.p, actual.q), actual.distance, 1e-12 * size);
    }
  }
}

TEST(MinimumDistance, SameAnswerForAnyThreadCountAndFromManyThreads) {
  const Scene scene = scenes().front();
  const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
  omp_set_num_threads(1);
  const MinimumDistance serial = minimumDistance(first, second);
  omp_set_num_threads(2);
  const MinimumDistance parallel = minimumDistance(first, second);
  EXPECT_EQ(parallel.distance, serial.distance);
  EXPECT_EQ(parallel.first, serial.first);
  EXPECT_EQ(parallel.second, serial.second);
  std::vector<MinimumDistance> answers(3);
  std::vector<std::thread> callers;
  for (MinimumDistance& answer : answers)
    callers.emplace_back([&] { answer = minimumDistance(first, second); });
  for (std::thread& caller : callers)
    caller.join();
  for (const MinimumDistance& answer : answers) {
    EXPECT_EQ(answer.distance, serial.distance);
    EXPECT_EQ(answer.first, serial.first);
    EXPECT_EQ(answer.second, serial.second);
  }
}

TEST(MinimumDistance, RejectsAnEmptyMesh) {
  EXPECT_THROW(minimumDistance(TriangleSoA(), flatten(primitives::box())), Error);
  EXPECT_THROW(minimumDistance(flatten(primitives::box()), TriangleSoA()), Error);
}

}  // namespace
}  // namespace delta::contactdetection
