// The hybrid solver is exact: on every pair of every family it returns the brute force's answer
// (distance to 1e-12 of the pair's size, the same intersect flag, the same closest points where
// they are unique), and the exact oracle's on a subset. Also printed: per family, the share of
// pairs the first (Newton-guided) stage left to the exhaustive stage and to the scalar brute
// force.
#include "delta/kernels/hybrid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "delta/kernels/penalty.h"
#include "delta/kernels/point_triangle.h"
#include "delta/kernels/segment_segment.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/kernels/triangle_triangle.h"

#include "kernels/exact_distance.h"
#include "kernels/pair_batch.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

using namespace test;  // the pair families and batches of triangle_pairs.h

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
constexpr double kTolerance = 1e-12;  // the contract, relative to the pair's size

struct CandidatePoints {
  double distance;
  Vec3 p, q;
};

/// The 15 candidate closest-point pairs of the brute force (6 vertex–face, 9 edge–edge),
/// computed by the scalar kernels.
std::vector<CandidatePoints> allCandidates(const Triangle& a, const Triangle& b) {
  const std::array<Vec3, 3> va{a.a, a.b, a.c}, vb{b.a, b.b, b.c};
  std::vector<CandidatePoints> candidates;
  for (int i = 0; i < 3; ++i) {
    const PointTriangleResult onA = closestPointOnTriangle(vb[i], a);
    candidates.push_back({std::sqrt(onA.distanceSquared), onA.closest, vb[i]});
    const PointTriangleResult onB = closestPointOnTriangle(va[i], b);
    candidates.push_back({std::sqrt(onB.distanceSquared), va[i], onB.closest});
    for (int j = 0; j < 3; ++j) {
      const SegmentSegmentResult s =
          closestPointsOnSegments(va[i], va[(i + 1) % 3], vb[j], vb[(j + 1) % 3]);
      candidates.push_back({std::sqrt(s.distanceSquared), s.p, s.q});
    }
  }
  return candidates;
}

/// Whether the closest points of two disjoint triangles are unique and well conditioned: every
/// candidate with other points is clearly further (parallel edges or faces give several
/// candidates at the same distance with different points).
bool uniqueClosestPoints(const Triangle& a, const Triangle& b, double size) {
  const auto candidates = allCandidates(a, b);
  const auto best = *std::min_element(
      candidates.begin(), candidates.end(),
      [](const CandidatePoints& x, const CandidatePoints& y) { return x.distance < y.distance; });
  if (best.distance < 1e-6 * size) return false;
  for (const CandidatePoints& c : candidates) {
    const bool samePoints = distance(c.p, best.p) + distance(c.q, best.q) <= 1e-9 * size;
    if (!samePoints && c.distance < best.distance + 1e-6 * size) return false;
  }
  return true;
}

/// Output coordinates are rounded in world coordinates: at 1e6, their spacing is ~1e-10.
double coordinateRounding(const Vec3& x) {
  return 8 * kEpsilon * maxAbs(x);
}

struct FamilyReport {
  std::size_t pairs = 0, rechecked = 0, fallbacks = 0, unique = 0;
  double worstDistance = 0.0, worstPoint = 0.0;
};

/// The pairs of `family`, every coordinate times 2^`exponent` (exact).
std::vector<std::pair<Triangle, Triangle>> scaledPairs(PairFamily family, std::size_t count,
                                                       std::uint64_t seed, int exponent) {
  std::vector<std::pair<Triangle, Triangle>> pairs = makePairs(family, count, seed);
  const auto scaled = [exponent](const Triangle& t) {
    return Triangle{ldexp(t.a, exponent), ldexp(t.b, exponent), ldexp(t.c, exponent)};
  };
  for (auto& [a, b] : pairs)
    a = scaled(a), b = scaled(b);
  return pairs;
}

FamilyReport checkAgainstBruteForce(PairFamily family, std::size_t count, std::uint64_t seed,
                                    Isa isa, int exponent = 0) {
  const PairBatch batch = makeBatch(scaledPairs(family, count, seed, exponent));
  PairResults results(batch.size());
  const BatchStatistics statistics = hybridDistances(batch.firstSoa, batch.secondSoa, results, isa);
  FamilyReport report;
  report.pairs = statistics.pairs;
  report.rechecked = statistics.rechecked;
  report.fallbacks = statistics.fallbacks;
  EXPECT_EQ(statistics.pairs, batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) {
    const Triangle& a = batch.first[i];
    const Triangle& b = batch.second[i];
    const double size = pairSize(a, b);
    const TriangleDistanceResult exact = triangleDistanceBruteForce(a, b);
    const double difference = std::fabs(results.distance(i) - std::sqrt(exact.distanceSquared));
    report.worstDistance = std::max(report.worstDistance, difference / size);
    EXPECT_LE(difference, kTolerance * size) << name(family) << " pair " << i << "\n"
                                             << pasteable(a, b);
    EXPECT_EQ(results.intersect(i), exact.intersect) << name(family) << " pair " << i << "\n"
                                                     << pasteable(a, b);
    EXPECT_TRUE(results.converged(i));
    EXPECT_EQ(results.errorBound(i), 0.0);
    if (results.intersect(i)) {
      EXPECT_EQ(results.distanceSquared(i), 0.0);
      EXPECT_EQ(results.p(i), results.q(i));
    } else if (uniqueClosestPoints(a, b, size)) {
      ++report.unique;
      const double apart = std::max(distance(results.p(i), exact.p) - coordinateRounding(exact.p),
                                    distance(results.q(i), exact.q) - coordinateRounding(exact.q));
      report.worstPoint = std::max(report.worstPoint, apart / size);
      EXPECT_LE(apart, 1e-9 * size) << name(family) << " pair " << i << "\n" << pasteable(a, b);
    }
  }
  return report;
}

// ≥ 10⁵ pairs over all families (Release; a twentieth under sanitizers), on the default ISA.
TEST(Hybrid, MatchesTheBruteForceOnEveryFamily) {
  std::printf("%-20s %8s %10s %10s %12s %12s %8s\n", "family", "pairs", "rechecked", "fallback",
              "max |Δd|/L", "max |Δp|/L", "unique");
  for (auto family : kAllFamilies) {
    const FamilyReport r =
        checkAgainstBruteForce(family, test::scaledCount(8000), 79, defaultIsa());
    const double pairs = static_cast<double>(r.pairs);
    std::printf("%-20s %8zu %9.2f%% %9.2f%% %12.2e %12.2e %8zu\n", name(family), r.pairs,
                100 * static_cast<double>(r.rechecked) / pairs,
                100 * static_cast<double>(r.fallbacks) / pairs, r.worstDistance, r.worstPoint,
                r.unique);
    ::testing::Test::RecordProperty(std::string("fallback_rate_") + name(family),
                                    std::to_string(static_cast<double>(r.fallbacks) / pairs));
    ::testing::Test::RecordProperty(std::string("recheck_rate_") + name(family),
                                    std::to_string(static_cast<double>(r.rechecked) / pairs));
    // What the Newton-guided stage is for: near contacts and far pairs rarely need more.
    if (family == PairFamily::NearContact || family == PairFamily::Far) {
      EXPECT_LE(r.rechecked, r.pairs / 20) << name(family);  // measured ≈ 3% and 0.1%
      EXPECT_LE(r.fallbacks, r.pairs / 200) << name(family);
    }
  }
}

TEST(Hybrid, EveryIsaMatchesTheBruteForce) {
  for (Isa isa : supportedIsas())
    for (auto family : kAllFamilies) {
      SCOPED_TRACE(name(isa));
      checkAgainstBruteForce(family, test::scaledCount(1000), 83, isa);
    }
}

TEST(Hybrid, TinyAndHugePairsMatchTheBruteForce) {
  // Found by audits: below about 2⁻¹⁴² the piercing test's products (degree 7 in the pair's
  // size) underflowed to 0 and passed as 0 ≥ 0, so granulates scaled by 2⁻¹⁶⁰ were reported
  // intersecting 0.13 of their size apart; above about 2¹⁴⁶ they overflowed and ∞ ≥ margin
  // passed. Every family at such scales, on every ISA.
  for (Isa isa : supportedIsas())
    for (const int exponent : {-130, -150, -160, -175, 125, 140, 146, 147, 150, 170})
      for (auto family : kAllFamilies) {
        SCOPED_TRACE(std::string(name(isa)) + " 2^" + std::to_string(exponent));
        checkAgainstBruteForce(family, test::scaledCount(300), 97, isa, exponent);
      }
  // The pair the review found at 2¹⁴⁶ (scalar and SSE2 reported it intersecting): an edge of B
  // beside A's face, 0.028 of the size apart.
  const double s = 0x1p146, c = 0.52 * s;
  const Triangle a{{0, 0, 0}, {s, 0, 0}, {0, s, 0}};
  const Triangle b{{c, c, 2 * s}, {c, c, -2 * s}, {c + 0.2 * s, c + 0.2 * s, -2 * s}};
  const TriangleDistanceResult exact = triangleDistanceBruteForce(a, b);
  ASSERT_FALSE(exact.intersect);
  for (Isa isa : supportedIsas()) {
    const PairBatch batch = makeBatch({{a, b}});
    PairResults results(1);
    hybridDistances(batch.firstSoa, batch.secondSoa, results, isa);
    EXPECT_FALSE(results.intersect(0)) << name(isa);
    EXPECT_NEAR(results.distance(0), std::sqrt(exact.distanceSquared), 1e-12 * s) << name(isa);
  }
}

TEST(Hybrid, MatchesTheExactOracle) {
  for (auto family : kAllFamilies) {
    const PairBatch batch = makeBatch(makePairs(family, test::scaledCount(200), 89));
    PairResults results(batch.size());
    hybridDistances(batch.firstSoa, batch.secondSoa, results);
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const Triangle& a = batch.first[i];
      const Triangle& b = batch.second[i];
      const double size = pairSize(a, b);
      const double exact = std::sqrt(test::exactSquaredDistance(a, b));
      EXPECT_NEAR(results.distance(i), exact, kTolerance * size)
          << name(family) << " pair " << i << "\n"
          << pasteable(a, b);
      // Touching counts as intersecting; a pair reported intersecting is within rounding of it.
      if (test::exactIntersect(a, b)) {
        EXPECT_TRUE(results.intersect(i)) << pasteable(a, b);
      }
      if (results.intersect(i)) {
        EXPECT_LE(exact, kTolerance * size) << pasteable(a, b);
      }
    }
  }
}

TEST(Hybrid, IntersectAgreesWithTrianglesIntersect) {
  for (auto family : kAllFamilies) {
    const PairBatch batch = makeBatch(makePairs(family, test::scaledCount(2000), 97));
    PairResults results(batch.size());
    hybridDistances(batch.firstSoa, batch.secondSoa, results);
    for (std::size_t i = 0; i < batch.size(); ++i)
      EXPECT_EQ(results.intersect(i), trianglesIntersect(batch.first[i], batch.second[i]))
          << name(family) << " pair " << i << "\n"
          << pasteable(batch.first[i], batch.second[i]);
  }
}

TEST(Hybrid, SymmetricInTheOrderOfThePair) {
  for (auto family : kAllFamilies) {
    const auto pairs = makePairs(family, test::scaledCount(1000), 101);
    std::vector<std::pair<Triangle, Triangle>> swapped;
    for (const auto& [a, b] : pairs)
      swapped.push_back({b, a});
    const PairBatch batch = makeBatch(pairs), back = makeBatch(swapped);
    PairResults forward(batch.size()), backward(batch.size());
    hybridDistances(batch.firstSoa, batch.secondSoa, forward);
    hybridDistances(back.firstSoa, back.secondSoa, backward);
    for (std::size_t i = 0; i < batch.size(); ++i) {
      const double size = pairSize(batch.first[i], batch.second[i]);
      EXPECT_NEAR(forward.distance(i), backward.distance(i), 2 * kTolerance * size)
          << name(family) << "\n"
          << pasteable(batch.first[i], batch.second[i]);
      EXPECT_EQ(forward.intersect(i), backward.intersect(i))
          << name(family) << "\n"
          << pasteable(batch.first[i], batch.second[i]);
    }
  }
}

TEST(Hybrid, IntersectingPairsAreConfirmedWithoutTheBruteForce) {
  // Edges piercing faces clearly: the first stage certifies them (p = q on both triangles).
  const PairBatch batch =
      makeBatch(makePairs(PairFamily::EdgeThroughFace, test::scaledCount(2000), 103));
  PairResults results(batch.size());
  const BatchStatistics statistics = hybridDistances(batch.firstSoa, batch.secondSoa, results);
  std::size_t intersecting = 0;
  for (std::size_t i = 0; i < batch.size(); ++i) {
    if (!results.intersect(i)) continue;
    ++intersecting;
    const double slack = 1e-12 * pairSize(batch.first[i], batch.second[i]);
    EXPECT_LE(std::sqrt(test::exactSquaredDistance(results.p(i), batch.first[i])), slack);
    EXPECT_LE(std::sqrt(test::exactSquaredDistance(results.p(i), batch.second[i])), slack);
  }
  EXPECT_GT(intersecting, batch.size() / 2);
  // The T-shaped tenth (an edge ending exactly on the face) touches: only those may fall back.
  EXPECT_LE(statistics.fallbacks, batch.size() / 5);
}

TEST(Hybrid, KnownPairs) {
  const Triangle unit{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Triangle spike{{0.25, 0.25, 0.5}, {0, 0, 3}, {1, 1, 3}};        // vertex 0.5 above
  const Triangle skew{{0.5, -1, -1}, {0.5, -1, 1}, {0.5, -3, 0}};       // edges 1 apart
  const Triangle pierce{{0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.6, 0.2, 1}};  // edge through the face
  const Triangle touch{{1, 0, 0}, {2, 0, 1}, {2, 1, 1}};                // shares a vertex
  const PairBatch batch = makeBatch({{unit, spike}, {unit, skew}, {unit, pierce}, {unit, touch}});
  PairResults results(4);
  const BatchStatistics statistics = hybridDistances(batch.firstSoa, batch.secondSoa, results);
  EXPECT_NEAR(results.distance(0), 0.5, 1e-15);
  EXPECT_EQ(results.q(0), spike.a);
  EXPECT_NEAR(distance(results.p(0), {0.25, 0.25, 0}), 0.0, 1e-15);
  EXPECT_NEAR(results.distance(1), 1.0, 1e-15);
  EXPECT_TRUE(results.intersect(2));
  EXPECT_NEAR(distance(results.p(2), {0.2, 0.2, 0}), 0.0, 1e-15);  // where the edge pierces
  EXPECT_TRUE(results.intersect(3));
  EXPECT_EQ(results.distanceSquared(3), 0.0);
  EXPECT_GE(statistics.fallbacks, 1u);  // exact touching is the brute force's to decide
}

}  // namespace
}  // namespace delta::kernels

namespace delta::kernels {
namespace {

// A pair's answer is the same bits in any batch: alone, or among others at any place (the DEM's
// contact caches hand the kernels the same pairs in other batches than a fresh query would;
// query/contacts.h, ContactCache). Every family, every ISA, the hybrid and the penalty solver;
// the hybrid's stage-2 pairs of a batch come out one, several or none in the sizes below.
TEST(Hybrid, APairsAnswerDoesNotDependOnItsBatch) {
  for (Isa isa : supportedIsas())
    for (auto family : kAllFamilies) {
      SCOPED_TRACE(name(isa));
      const test::PairBatch batch = test::makeBatch(test::makePairs(family, 120, 29));
      for (const bool penalty : {false, true}) {
        const auto solve = [&](const TriangleSoA& first, const TriangleSoA& second,
                               PairResults& results) {
          penalty ? penaltyDistances(first, second, results, isa)
                  : hybridDistances(first, second, results, isa);
        };
        PairResults whole(batch.size());
        solve(batch.firstSoa, batch.secondSoa, whole);
        std::size_t mismatches = 0;
        for (std::size_t size : {1, 2, 3, 7, 17}) {
          for (std::size_t begin = 0; begin + size <= batch.size(); begin += size) {
            const std::vector<Triangle> first(batch.first.begin() + begin,
                                              batch.first.begin() + begin + size);
            const std::vector<Triangle> second(batch.second.begin() + begin,
                                               batch.second.begin() + begin + size);
            PairResults part(size);
            solve(test::flattenTriangles(first), test::flattenTriangles(second), part);
            for (std::size_t k = 0; k < size; ++k) {
              const std::size_t i = begin + k;
              const bool same = part.distanceSquared(k) == whole.distanceSquared(i) &&
                                part.p(k) == whole.p(i) && part.q(k) == whole.q(i) &&
                                part.intersect(k) == whole.intersect(i);
              mismatches += same ? 0 : 1;
            }
          }
        }
        EXPECT_EQ(mismatches, 0u) << test::name(family) << (penalty ? ", penalty" : ", hybrid");
      }
    }
}

// The DEM case: user threads call the hybrid at once on shared, const triangle blocks (each with
// its own results). Every thread gets the serial answer, bit for bit; run under TSan in CI.
TEST(Hybrid, ManyThreadsShareTheBlocks) {
  const test::PairBatch batch =
      test::makeBatch(test::makePairs(test::PairFamily::NearContact, 999, 5));
  PairResults serial(batch.size());
  hybridDistances(batch.firstSoa, batch.secondSoa, serial);
  std::vector<PairResults> results(4, PairResults(batch.size()));
  std::vector<std::thread> threads;
  for (PairResults& mine : results)
    threads.emplace_back([&batch, &mine] {
      for (int repeat = 0; repeat < 3; ++repeat)
        hybridDistances(batch.firstSoa, batch.secondSoa, mine);
    });
  for (std::thread& thread : threads)
    thread.join();
  for (const PairResults& mine : results) {
    ASSERT_EQ(mine.size(), serial.size());
    for (std::size_t i = 0; i < serial.size(); ++i) {
      EXPECT_EQ(mine.distanceSquared(i), serial.distanceSquared(i)) << i;
      EXPECT_EQ(mine.intersect(i), serial.intersect(i)) << i;
    }
  }
}

}  // namespace
}  // namespace delta::kernels
