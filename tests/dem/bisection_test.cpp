#include "delta/dem/bisection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <barrier>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "delta/core/error.h"

namespace delta::dem {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

std::vector<Vec3> randomPoints(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  std::vector<Vec3> points(count);
  for (Vec3& p : points)
    p = {uniform(), uniform(), uniform()};
  return points;
}

/// The lower side's share of a node's points by the header's rule: points·⌊parts/2⌋/parts,
/// rounded to the nearest integer, halves down.
std::size_t lowerShare(std::size_t points, int parts) {
  const auto whole = static_cast<std::size_t>(parts), half = whole / 2;
  return (2 * points * half + whole - 1) / (2 * whole);
}

/// The count of every part by the rule, for points whose coordinates are distinct.
void countsByRule(std::size_t points, int parts, std::vector<std::size_t>& counts) {
  if (parts == 1) {
    counts.push_back(points);
    return;
  }
  const std::size_t lower = lowerShare(points, parts);
  countsByRule(lower, parts / 2, counts);
  countsByRule(points - lower, parts - parts / 2, counts);
}

/// The count of every part by the rule for points on a line (every cut along it), duplicates
/// included: where a run of equal coordinates straddles the target, the lower side gets the
/// nearer of the counts below the run and through it (below where both are as near).
void countsAlongALine(std::span<const double> sorted, int parts, std::vector<std::size_t>& counts) {
  if (parts == 1) {
    counts.push_back(sorted.size());
    return;
  }
  std::size_t lower = lowerShare(sorted.size(), parts);
  if (lower > 0 && sorted[lower - 1] == sorted[lower]) {
    const auto run = std::equal_range(sorted.begin(), sorted.end(), sorted[lower]);
    const auto below = static_cast<std::size_t>(run.first - sorted.begin());
    const auto through = static_cast<std::size_t>(run.second - sorted.begin());
    lower = lower - below <= through - lower ? below : through;
  }
  countsAlongALine(sorted.first(lower), parts / 2, counts);
  countsAlongALine(sorted.subspan(lower), parts - parts / 2, counts);
}

std::vector<std::size_t> countsByPart(const Bisection& bisection, std::span<const Vec3> points) {
  std::vector<std::size_t> counts(static_cast<std::size_t>(bisection.parts()), 0);
  for (const Vec3& p : points)
    ++counts[static_cast<std::size_t>(bisection.partOf(p))];
  return counts;
}

/// Whether the half-open region [lower, upper) holds x.
bool holds(const Aabb& region, const Vec3& x) {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (!(region.lower[axis] <= x[axis] && x[axis] < region.upper[axis])) return false;
  return true;
}

/// Points with coordinates on the cuts: every finite face of every region on one axis (the
/// others from `base`), and corners with all three coordinates on faces.
std::vector<Vec3> pointsOnCuts(const Bisection& bisection, const Vec3& base) {
  std::vector<double> faces[3];
  for (int part = 0; part < bisection.parts(); ++part) {
    const Aabb region = bisection.region(part);
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (double face : {region.lower[axis], region.upper[axis]})
        if (std::isfinite(face)) faces[axis].push_back(face);
  }
  std::vector<Vec3> points;
  for (std::size_t axis = 0; axis < 3; ++axis)
    for (double face : faces[axis]) {
      Vec3 p = base;
      p[axis] = face;
      points.push_back(p);
    }
  for (std::size_t i = 0; i < faces[0].size() && i < faces[1].size() && i < faces[2].size(); ++i)
    points.push_back({faces[0][i], faces[1][i], faces[2][i]});
  return points;
}

/// Checks that exactly one region holds each point, and that it is partOf's.
void expectRegionsTileAt(const Bisection& bisection, std::span<const Vec3> points) {
  for (const Vec3& x : points) {
    const int part = bisection.partOf(x);
    EXPECT_TRUE(holds(bisection.region(part), x)) << "part " << part;
    for (int other = 0; other < bisection.parts(); ++other) {
      if (other != part) {
        EXPECT_FALSE(holds(bisection.region(other), x)) << other << " " << part;
      }
    }
  }
}

/// Every part whose region box lies within `reach` of x, by brute force.
std::vector<int> partsWithinByDefinition(const Bisection& bisection, const Vec3& x, double reach) {
  std::vector<int> parts;
  for (int part = 0; part < bisection.parts(); ++part)
    if (std::sqrt(distanceSquared(x, bisection.region(part))) <= reach) parts.push_back(part);
  return parts;
}

TEST(DemBisection, OnePartIsAllOfSpace) {
  const std::vector<Vec3> points = randomPoints(10, 1);
  for (const Bisection& bisection : {Bisection(), Bisection(points, 1)}) {
    EXPECT_EQ(bisection.parts(), 1);
    EXPECT_EQ(bisection.partOf({1e300, -3, 0}), 0);
    const Aabb region = bisection.region(0);
    EXPECT_EQ(region.lower, (Vec3{-kInfinity, -kInfinity, -kInfinity}));
    EXPECT_EQ(region.upper, (Vec3{kInfinity, kInfinity, kInfinity}));
    std::vector<int> within;
    bisection.partsWithin({5, 5, 5}, 1.0, within);
    EXPECT_EQ(within, std::vector<int>{0});
  }
}

TEST(DemBisection, EveryPartGetsTheCountOfTheRule) {
  for (std::size_t count : {1000u, 1001u, 37u}) {
    const std::vector<Vec3> points = randomPoints(count, count);
    for (int parts = 1; parts <= 17; ++parts) {
      const Bisection bisection(points, parts);
      ASSERT_EQ(bisection.parts(), parts);
      std::vector<std::size_t> expected;
      countsByRule(count, parts, expected);
      const std::vector<std::size_t> counts = countsByPart(bisection, points);
      EXPECT_EQ(counts, expected) << count << " points, " << parts << " parts";
      for (std::size_t c : counts) {
        EXPECT_GE(c, count / static_cast<std::size_t>(parts));
        EXPECT_LE(c,
                  (count + static_cast<std::size_t>(parts) - 1) / static_cast<std::size_t>(parts));
      }
    }
  }
}

TEST(DemBisection, EachPointLiesInTheRegionOfItsPart) {
  const std::vector<Vec3> points = randomPoints(500, 7);
  const std::vector<Vec3> queries = randomPoints(200, 8);
  for (int parts = 1; parts <= 17; ++parts) {
    const Bisection bisection(points, parts);
    expectRegionsTileAt(bisection, points);
    expectRegionsTileAt(bisection, queries);
    expectRegionsTileAt(bisection, pointsOnCuts(bisection, {0.3, 0.6, 0.9}));
    expectRegionsTileAt(bisection, std::vector<Vec3>{{-1e300, 1e300, 0.5}, {5, -5, 2}});
  }
}

TEST(DemBisection, PartsWithinAgreesWithBruteForce) {
  const std::vector<Vec3> points = randomPoints(700, 11);
  std::mt19937_64 random(12);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  std::vector<int> within;
  for (int parts : {2, 3, 5, 8, 13, 17}) {
    const Bisection bisection(points, parts);
    std::vector<Vec3> queries = randomPoints(100, static_cast<std::uint64_t>(100 + parts));
    const std::vector<Vec3> onCuts = pointsOnCuts(bisection, {0.25, 0.5, 0.75});
    queries.insert(queries.end(), onCuts.begin(), onCuts.end());
    queries.push_back({-2, 3, 0.5});  // outside the points' box
    for (const Vec3& x : queries)
      for (double reach : {0.0, 0.05 * uniform(), 0.3 * uniform(), 2.0, kInfinity}) {
        bisection.partsWithin(x, reach, within);
        EXPECT_EQ(within, partsWithinByDefinition(bisection, x, reach))
            << parts << " parts, reach " << reach << " at " << x.x << " " << x.y << " " << x.z;
        EXPECT_TRUE(std::ranges::binary_search(within, bisection.partOf(x)));
      }
    bisection.partsWithin({0.5, 0.5, 0.5}, kInfinity, within);
    EXPECT_EQ(within.size(), static_cast<std::size_t>(parts));
  }
}

TEST(DemBisection, PointsAllEqualGoToTheLastPart) {
  const std::vector<Vec3> points(100, Vec3{0.5, -2, 3});
  for (int parts : {2, 5, 8}) {
    const Bisection bisection(points, parts);
    std::vector<std::size_t> expected(static_cast<std::size_t>(parts), 0);
    expected.back() = points.size();
    EXPECT_EQ(countsByPart(bisection, points), expected);
    expectRegionsTileAt(bisection, pointsOnCuts(bisection, {0.5, -2, 3}));
    expectRegionsTileAt(bisection, randomPoints(100, 3));
  }
}

TEST(DemBisection, DuplicatesAcrossACutGoToTheNearerSide) {
  // Points on the x axis: every cut is along x, and the rule can be followed along the line.
  std::mt19937_64 random(5);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  for (double duplicate : {0.5, 0.1, 0.9}) {
    std::vector<Vec3> points;
    for (int i = 0; i < 60; ++i) {
      points.push_back({duplicate, 0, 0});
      points.push_back({uniform(), 0, 0});
    }
    std::vector<double> sorted;
    for (const Vec3& p : points)
      sorted.push_back(p.x);
    std::ranges::sort(sorted);
    for (int parts = 2; parts <= 17; ++parts) {
      const Bisection bisection(points, parts);
      std::vector<std::size_t> expected;
      countsAlongALine(sorted, parts, expected);
      EXPECT_EQ(countsByPart(bisection, points), expected) << duplicate << ", " << parts;
      for (int part = 0; part + 1 < parts; ++part)
        EXPECT_EQ(bisection.region(part).upper.x, bisection.region(part + 1).lower.x);
      expectRegionsTileAt(bisection, pointsOnCuts(bisection, {0.5, 0, 0}));
    }
  }
}

TEST(DemBisection, NoPointsHalveTheCubeAroundTheOrigin) {
  const Bisection bisection(std::span<const Vec3>{}, 6);
  EXPECT_EQ(bisection.parts(), 6);
  for (int part = 0; part < 6; ++part) {
    const Aabb region = bisection.region(part);
    for (std::size_t axis = 0; axis < 3; ++axis) {
      EXPECT_LT(region.lower[axis], region.upper[axis]) << part;
      if (std::isfinite(region.lower[axis])) {
        EXPECT_GE(region.lower[axis], -1.0);
      }
      if (std::isfinite(region.upper[axis])) {
        EXPECT_LE(region.upper[axis], 1.0);
      }
    }
  }
  EXPECT_EQ(bisection.partOf({-0.5, -0.5, -0.5}), 0);
  expectRegionsTileAt(bisection, pointsOnCuts(bisection, {0.1, 0.2, 0.3}));
}

TEST(DemBisection, MorePartsThanPointsLeaveSomeEmpty) {
  const std::vector<Vec3> points = randomPoints(3, 9);
  const Bisection bisection(points, 8);
  const std::vector<std::size_t> counts = countsByPart(bisection, points);
  EXPECT_EQ(std::ranges::count(counts, 1u), 3);
  EXPECT_EQ(std::ranges::count(counts, 0u), 5);
  expectRegionsTileAt(bisection, points);
  expectRegionsTileAt(bisection, pointsOnCuts(bisection, {0.5, 0.5, 0.5}));
}

TEST(DemBisection, RejectsBadInput) {
  const std::vector<Vec3> points = randomPoints(10, 4);
  EXPECT_THROW(Bisection(points, 0), Error);
  EXPECT_THROW(Bisection(points, -3), Error);
  EXPECT_THROW(Bisection(points, Bisection::kMaxParts + 1), Error);
  std::vector<Vec3> bad = points;
  bad[7].y = std::nan("");
  try {
    Bisection(bad, 4);
    ADD_FAILURE() << "a NaN point was accepted";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("point 7"), std::string::npos) << message;
    EXPECT_NE(message.find("nan"), std::string::npos) << message;
  }
  bad[7].y = kInfinity;
  EXPECT_THROW(Bisection(bad, 1), Error);

  const Bisection bisection(points, 4);
  std::vector<int> within;
  EXPECT_THROW(bisection.partsWithin({0, 0, 0}, -1.0, within), Error);
  EXPECT_THROW(bisection.partsWithin({0, 0, 0}, std::nan(""), within), Error);
  EXPECT_THROW(bisection.partsWithin({0, std::nan(""), 0}, 1.0, within), Error);
  EXPECT_THROW(bisection.region(-1), Error);
  EXPECT_THROW(bisection.region(4), Error);
}

TEST(DemBisection, EqualWeightsGiveTheCutsOfCounts) {
  const std::vector<Vec3> points = randomPoints(500, 51);
  const std::vector<std::uint32_t> threes(points.size(), 3);
  for (int parts = 1; parts <= 9; ++parts) {
    const Bisection counted(points, parts), weighted(points, threes, parts);
    for (int part = 0; part < parts; ++part) {
      const Aabb a = counted.region(part), b = weighted.region(part);
      EXPECT_EQ(a.lower, b.lower) << parts << " parts, part " << part;
      EXPECT_EQ(a.upper, b.upper) << parts << " parts, part " << part;
    }
  }
}

TEST(DemBisection, PartsGetAboutEqualWeight) {
  // Points with x < 1 weigh 40 (the busy half of a hopper), the others 1: the parts over the
  // heavy half hold fewer points, every part about the same weight.
  std::vector<Vec3> points = randomPoints(2000, 53);
  for (Vec3& p : points)
    p.x *= 2.0;  // so that the first cut is along x
  std::vector<std::uint32_t> weights;
  std::uint64_t total = 0;
  for (const Vec3& p : points) {
    weights.push_back(p.x < 1.0 ? 40 : 1);
    total += weights.back();
  }
  for (int parts = 2; parts <= 9; ++parts) {
    const Bisection bisection(points, weights, parts);
    std::vector<std::uint64_t> weightOf(static_cast<std::size_t>(parts), 0);
    for (std::size_t i = 0; i < points.size(); ++i)
      weightOf[static_cast<std::size_t>(bisection.partOf(points[i]))] += weights[i];
    const double mean = static_cast<double>(total) / parts;
    const int levels = std::bit_width(static_cast<unsigned>(parts - 1));
    for (int part = 0; part < parts; ++part)  // each cut is off by at most one point's weight
      EXPECT_LE(std::fabs(static_cast<double>(weightOf[static_cast<std::size_t>(part)]) - mean),
                40.0 * levels)
          << parts << " parts, part " << part;
    // The same parts by count would be far apart in weight.
    const Bisection counted(points, parts);
    std::vector<std::uint64_t> countedWeight(static_cast<std::size_t>(parts), 0);
    for (std::size_t i = 0; i < points.size(); ++i)
      countedWeight[static_cast<std::size_t>(counted.partOf(points[i]))] += weights[i];
    EXPECT_GT(static_cast<double>(*std::max_element(countedWeight.begin(), countedWeight.end())),
              1.5 * mean);
  }
}

TEST(DemBisection, RejectsBadWeights) {
  const std::vector<Vec3> points = randomPoints(10, 57);
  std::vector<std::uint32_t> weights(points.size(), 2);
  weights[4] = 0;
  EXPECT_THROW(Bisection(points, weights, 3), Error);
  weights.pop_back();
  weights[4] = 2;
  EXPECT_THROW(Bisection(points, weights, 3), Error);
  weights.push_back(2);
  EXPECT_NO_THROW(Bisection(points, weights, 3));
}

TEST(DemBisection, CostsOneMaximumAndAFewSumsALevel) {
  const std::vector<Vec3> points = randomPoints(20000, 21);
  int sums = 0, maxima = 0;
  const BisectionReduction counting{[&sums](std::span<std::uint64_t>) { ++sums; },
                                    [&maxima](std::span<double>) { ++maxima; }};
  const Bisection bisection(points, 16, counting);
  const int levels = 4;  // below the root
  EXPECT_EQ(maxima, 1 + levels);
  EXPECT_GE(sums, 1 + levels);
  EXPECT_LE(sums, 1 + 8 * levels);
  EXPECT_EQ(countsByPart(bisection, points), std::vector<std::size_t>(16, 1250));
}

/// MPI_Allreduce for threads that share one decomposition: each thread posts its values in its
/// own slot, waits for every thread, combines the slots in thread order (so every thread gets the
/// same bits), and waits again before any slot is written for the next call.
class ThreadReduction {
 public:
  explicit ThreadReduction(int threads)
      : barrier_(threads),
        sums_(static_cast<std::size_t>(threads)),
        maxima_(static_cast<std::size_t>(threads)) {}

  BisectionReduction forThread(std::size_t thread) {
    return {[this, thread](std::span<std::uint64_t> values) {
              combine(thread, values, sums_,
                      [](std::uint64_t a, std::uint64_t b) { return a + b; });
            },
            [this, thread](std::span<double> values) {
              combine(thread, values, maxima_, [](double a, double b) { return std::max(a, b); });
            }};
  }

 private:
  template <typename T, typename Combine>
  void combine(std::size_t thread, std::span<T> values, std::vector<std::vector<T>>& slots,
               Combine combineTwo) {
    slots[thread].assign(values.begin(), values.end());
    barrier_.arrive_and_wait();
    for (const std::vector<T>& slot : slots)
      EXPECT_EQ(slot.size(), values.size()) << "the threads' calls differ";
    for (std::size_t i = 0; i < values.size(); ++i) {
      T combined = slots[0][i];
      for (std::size_t other = 1; other < slots.size(); ++other)
        if (i < slots[other].size()) combined = combineTwo(combined, slots[other][i]);
      values[i] = combined;
    }
    barrier_.arrive_and_wait();
  }

  std::barrier<> barrier_;
  std::vector<std::vector<std::uint64_t>> sums_;
  std::vector<std::vector<double>> maxima_;
};

/// What each of `threads` threads built from its share of the points (thread t gets the points
/// i with i % (threads + 1) == t, the last thread also those with remainder `threads`, so the
/// shares differ in size), or the message of what it threw.
struct ThreadResult {
  std::optional<Bisection> bisection;
  std::string error;
};

std::vector<ThreadResult> buildOnThreads(std::span<const Vec3> points, std::span<const int> parts) {
  const std::size_t threads = parts.size();
  std::vector<std::vector<Vec3>> shares(threads);
  for (std::size_t i = 0; i < points.size(); ++i)
    shares[std::min(i % (threads + 1), threads - 1)].push_back(points[i]);
  ThreadReduction reduction(static_cast<int>(threads));
  std::vector<ThreadResult> results(threads);
  {
    std::vector<std::jthread> running;
    for (std::size_t t = 0; t < threads; ++t)
      running.emplace_back([&, t] {
        try {
          results[t].bisection.emplace(shares[t], parts[t], reduction.forThread(t));
        } catch (const Error& error) {
          results[t].error = error.what();
        }
      });
  }
  return results;
}

/// The bits of a point's coordinates, to compare cuts bit for bit.
std::array<std::uint64_t, 3> bits(const Vec3& p) {
  return std::bit_cast<std::array<std::uint64_t, 3>>(p);
}

TEST(DemBisection, SameCutsForFourThreadsSharingThePoints) {
  std::vector<Vec3> many = randomPoints(3000, 31);
  many.insert(many.end(), 150, Vec3{0.25, 0.5, 0.75});  // a run of duplicates
  const std::vector<Vec3> few = randomPoints(3, 32);    // the fourth thread gets none
  for (const std::vector<Vec3>& points : {many, few})
    for (int parts : {1, 2, 7, 13}) {
      const Bisection alone(points, parts);
      const std::vector<int> sameParts(4, parts);
      for (const ThreadResult& result : buildOnThreads(points, sameParts)) {
        ASSERT_TRUE(result.bisection) << result.error;
        const Bisection& shared = *result.bisection;
        ASSERT_EQ(shared.parts(), parts);
        for (int part = 0; part < parts; ++part) {
          EXPECT_EQ(bits(shared.region(part).lower), bits(alone.region(part).lower)) << part;
          EXPECT_EQ(bits(shared.region(part).upper), bits(alone.region(part).upper)) << part;
        }
        for (const Vec3& p : points)
          ASSERT_EQ(shared.partOf(p), alone.partOf(p));
      }
    }
}

TEST(DemBisection, EveryThreadThrowsWhenOneThreadHasABadPointOrOtherParts) {
  std::vector<Vec3> points = randomPoints(400, 41);
  points[5].z = std::nan("");  // on thread 0 (5 % 5 == 0)
  const std::vector<int> parts(4, 6);
  for (const ThreadResult& result : buildOnThreads(points, parts)) {
    EXPECT_FALSE(result.bisection);
    EXPECT_NE(result.error.find("not finite"), std::string::npos) << result.error;
  }
  points[5].z = 0.5;
  const std::vector<int> disagreeing = {6, 6, 5, 6};
  for (const ThreadResult& result : buildOnThreads(points, disagreeing)) {
    EXPECT_FALSE(result.bisection);
    EXPECT_NE(result.error.find("disagree"), std::string::npos) << result.error;
  }
}

}  // namespace
}  // namespace delta::dem
