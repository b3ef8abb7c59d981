#include "delta/dem/broad_phase.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "delta/core/error.h"

namespace delta::dem {
namespace {

std::vector<Sphere> randomSpheres(std::size_t count, double box, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  std::vector<Sphere> spheres(count);
  for (Sphere& sphere : spheres) {
    sphere.center = {box * uniform(), box * uniform(), box * uniform()};
    sphere.radius = 0.5 + 0.5 * uniform();
  }
  return spheres;
}

std::vector<CandidatePair> pairsByDefinition(const std::vector<Sphere>& spheres, double margin) {
  std::vector<CandidatePair> pairs;
  for (std::size_t i = 0; i < spheres.size(); ++i)
    for (std::size_t j = i + 1; j < spheres.size(); ++j) {
      const double reach = spheres[i].radius + spheres[j].radius + margin;
      if (distanceSquared(spheres[i].center, spheres[j].center) < reach * reach)
        pairs.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
    }
  return pairs;
}

TEST(DemBroadPhase, FindsExactlyThePairsOfTheDefinitionInOrder) {
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const std::vector<Sphere> spheres = randomSpheres(2000, 30.0, seed);
    const std::vector<CandidatePair> expected = pairsByDefinition(spheres, 0.1);
    EXPECT_GT(expected.size(), 1000u);
    EXPECT_EQ(nearbyPairs(spheres, 0.1), expected) << "seed " << seed;
  }
}

TEST(DemBroadPhase, SpheresOfVeryDifferentSizesGetThePairsOfTheDefinition) {
  // One sphere of radius 5 among 64,000 of 0.01 made the cells 10 wide: 4.6 s a call, against
  // 0.04 s without it (found by an audit). Sizes apart by more than a factor 2 now get cells of
  // their own level. Mixes against the definition, on one and two threads.
  std::mt19937_64 random(11);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  const auto placed = [&](std::size_t count, double box, const auto& radius) {
    std::vector<Sphere> spheres(count);
    for (Sphere& sphere : spheres)
      sphere = {{box * uniform(), box * uniform(), box * uniform()}, radius()};
    return spheres;
  };
  std::vector<std::vector<Sphere>> mixes;
  // Small grains and a boulder (in the middle and at a corner).
  mixes.push_back(placed(3000, 1.0, [&] { return 0.01 + 0.01 * uniform(); }));
  mixes.back()[17] = {{0.5, 0.5, 0.5}, 0.3};
  mixes.back()[2999] = {{0.0, 1.0, 0.0}, 0.2};
  // Two sizes five apart, half and half.
  mixes.push_back(placed(3000, 3.0, [&] { return uniform() < 0.5 ? 0.02 : 0.1; }));
  // Radii spread over three decades (log-uniform), and some points of radius 0.
  mixes.push_back(placed(3000, 2.0, [&] { return 0.001 * std::pow(1000.0, uniform()); }));
  for (std::size_t i = 0; i < 3000; i += 97)
    mixes.back()[i].radius = 0.0;
  const int threads = omp_get_max_threads();
  for (std::size_t m = 0; m < mixes.size(); ++m)
    for (const double margin : {0.0, 0.005}) {
      const std::vector<CandidatePair> expected = pairsByDefinition(mixes[m], margin);
      EXPECT_GT(expected.size(), 500u) << "mix " << m;
      for (const int count : {1, 2}) {
        omp_set_num_threads(count);
        EXPECT_EQ(nearbyPairs(mixes[m], margin), expected)
            << "mix " << m << ", margin " << margin << ", " << count << " threads";
      }
    }
  omp_set_num_threads(threads);
}

TEST(DemBroadPhase, FarApartAndCoincidentSpheres) {
  std::vector<Sphere> spheres = {
      {{0, 0, 0}, 1}, {{1e9, 0, 0}, 1}, {{1e9, 1.5, 0}, 1}, {{0, 0, 0}, 1}, {{-1e9, -1e9, 1e9}, 1}};
  EXPECT_EQ(nearbyPairs(spheres, 0.0), pairsByDefinition(spheres, 0.0));
  EXPECT_EQ(nearbyPairs(spheres, 0.0).size(), 2u);
  EXPECT_TRUE(nearbyPairs(std::vector<Sphere>{{{0, 0, 0}, 0}, {{0, 0, 0}, 0}}, 0.0).empty());
  EXPECT_TRUE(nearbyPairs(std::vector<Sphere>{}, 1.0).empty());
}

TEST(DemBroadPhase, SpheresJustWithinReachAreFoundWhereTheirCellsRound) {
  // Found by a review: the reach equal to the cell's edge, (c − lower) / edge rounded the second
  // and third spheres, 4.5e-14 inside each other's reach, into cells two apart.
  const double r = 0.10145294357308786;
  const std::vector<Sphere> spheres = {{{-3.249042560330531, 0, 0}, r},
                                       {{1022.0344051892953, 0, 0}, r},
                                       {{1022.2373110764414, 0, 0}, r}};
  ASSERT_EQ(pairsByDefinition(spheres, 0.0).size(), 1u);
  EXPECT_EQ(nearbyPairs(spheres, 0.0), pairsByDefinition(spheres, 0.0));
}

TEST(DemBroadPhase, SameForOneAndTwoThreads) {
  const std::vector<Sphere> spheres = randomSpheres(3000, 40.0, 7);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<CandidatePair> one = nearbyPairs(spheres, 0.2);
  omp_set_num_threads(2);
  const std::vector<CandidatePair> two = nearbyPairs(spheres, 0.2);
  omp_set_num_threads(threads);
  EXPECT_EQ(one, two);
}

TEST(DemBroadPhase, RejectsBadInput) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(nearbyPairs(std::vector<Sphere>{{{0, 0, 0}, 1}}, -1.0), Error);
  EXPECT_THROW(nearbyPairs(std::vector<Sphere>{{{0, 0, 0}, 1}}, nan), Error);
  EXPECT_THROW(nearbyPairs(std::vector<Sphere>{{{nan, 0, 0}, 1}}, 0.0), Error);
  EXPECT_THROW(nearbyPairs(std::vector<Sphere>{{{0, 0, 0}, -1}}, 0.0), Error);
}

TEST(DemBroadPhase, RefusesLengthsWhoseSquaresLeaveTheDoubles) {
  // An audit's cases, each one pair by the definition and none found: the reach's square
  // underflowed (coincident spheres of radius 1e-170; points 1e-170 apart, margin 1e-169) or the
  // squares overflowed (radius 1e200, centres 1e170 apart). Now refused.
  const std::vector<Sphere> tiny = {{{1, 1, 1}, 1e-170}, {{1, 1, 1}, 1e-170}};
  EXPECT_THROW(nearbyPairs(tiny, 0.0), Error);
  const std::vector<Sphere> points = {{{0, 0, 0}, 0.0}, {{1e-170, 0, 0}, 0.0}};
  EXPECT_THROW(nearbyPairs(points, 1e-169), Error);
  const std::vector<Sphere> huge = {{{0, 0, 0}, 1e200}, {{1e170, 0, 0}, 1e200}};
  EXPECT_THROW(nearbyPairs(huge, 0.0), Error);
  EXPECT_THROW(nearbyPairs(std::vector<Sphere>{{{1e61, 0, 0}, 1}}, 0.0), Error);
  // At the ends of the range the definition holds.
  const std::vector<Sphere> smallest = {{{1, 1, 1}, 0x1p-481}, {{1, 1, 1}, 0x1p-481}};
  EXPECT_EQ(nearbyPairs(smallest, 0.0).size(), 1u);
  const std::vector<Sphere> largest = {{{0, 0, 0}, 0x1p199}, {{-0x1.8p199, 0, 0}, 0x1p199}};
  EXPECT_EQ(nearbyPairs(largest, 0x1p-481), pairsByDefinition(largest, 0x1p-481));
  EXPECT_EQ(nearbyPairs(largest, 0x1p-481).size(), 1u);
}

}  // namespace
}  // namespace delta::dem
