// The run-time choice of instruction set for the batched triangle solvers, and what every ISA
// must share: the same results as the one-lane reference (Isa::Scalar), batches of any size, and
// no output beyond the pairs asked for.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "delta/kernels/isa.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/kernels/triangle_triangle.h"

#include "kernels/pair_batch.h"
#include "kernels/triangle_pairs.h"

namespace delta::kernels {
namespace {

using test::kAllFamilies;
using test::makeBatch;
using test::makePairs;
using test::name;
using test::PairBatch;
using test::pairSize;
using test::pasteable;

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

constexpr Isa kEveryIsa[] = {Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512, Isa::Neon, Isa::Sve};

TEST(KernelDispatch, NamesRoundTrip) {
  for (Isa isa : kEveryIsa) {
    EXPECT_EQ(parseIsa(name(isa)), isa);
    EXPECT_GE(laneCount(isa), 1);
  }
  EXPECT_EQ(laneCount(Isa::Scalar), 1);
  EXPECT_EQ(laneCount(Isa::Avx512), 8);
  EXPECT_EQ(laneCount(Isa::Neon), 2);
  EXPECT_FALSE(parseIsa("avx1024").has_value());
  EXPECT_FALSE(parseIsa("").has_value());
  for (Solver solver : {Solver::BruteForce, Solver::Penalty, Solver::Hybrid})
    EXPECT_EQ(parseSolver(name(solver)), solver);
  EXPECT_FALSE(parseSolver("newton").has_value());
}

TEST(KernelDispatch, ChoosesASupportedIsaOnce) {
  const std::vector<Isa> isas = supportedIsas();
  ASSERT_FALSE(isas.empty());
  EXPECT_EQ(isas.front(), Isa::Scalar);
  EXPECT_TRUE(std::is_sorted(isas.begin(), isas.end()));
  EXPECT_TRUE(isSupported(defaultIsa()));
  EXPECT_EQ(defaultIsa(), defaultIsa());
  for (Isa isa : kEveryIsa) {
    const Isa lowered = supportedIsaAtMost(isa);
    EXPECT_TRUE(isSupported(lowered));
    EXPECT_LE(lowered, isa);
    if (isSupported(isa)) {
      EXPECT_EQ(lowered, isa);
    }
  }
#if defined(__x86_64__)
  EXPECT_TRUE(isSupported(Isa::Sse2));  // the x86-64 baseline
  EXPECT_FALSE(isSupported(Isa::Neon));
  EXPECT_EQ(supportedIsaAtMost(Isa::Sve), Isa::Scalar);  // another architecture's: not lowered
#elif defined(__aarch64__)
  EXPECT_TRUE(isSupported(Isa::Neon));  // the AArch64 baseline
  EXPECT_FALSE(isSupported(Isa::Avx2));
  EXPECT_EQ(supportedIsaAtMost(Isa::Avx512), Isa::Scalar);
#endif
  std::string list;
  for (Isa isa : isas)
    list += std::string(name(isa)) + " ";
  ::testing::Test::RecordProperty("supported_isas", list);
  std::printf("supported ISAs: %sdefault %s\n", list.c_str(), name(defaultIsa()));
}

// The penalty iteration is the same arithmetic on every ISA. Without FMA (SSE2) it is the same
// to the bit as the scalar reference. With FMA (AVX2, AVX-512, and AArch64's tables, which may
// fuse where their compiler sees fit) the roundings differ in the last bits and the
// ill-conditioned Newton systems (ρ/α up to 10¹⁶) amplify them, so an unconverged
// pair may end elsewhere; what holds: pairs converged on both agree within their certified error
// bounds, and the converged flag rarely differs.
TEST(KernelDispatch, EveryIsaPenaltyMatchesTheScalarReference) {
  for (Isa isa : supportedIsas()) {
    if (isa == Isa::Scalar) continue;
    // AArch64's compilers fuse a·b + c wherever they see it, in each table as they see fit.
    const bool fused = isa != Isa::Sse2;
    std::size_t pairs = 0, flagDiffers = 0, bothConverged = 0;
    double worstUlps = 0.0;
    for (auto family : kAllFamilies) {
      const PairBatch batch = makeBatch(makePairs(family, test::scaledCount(2000), 31));
      PairResults reference(batch.size()), results(batch.size());
      penaltyDistances(batch.firstSoa, batch.secondSoa, reference, Isa::Scalar);
      penaltyDistances(batch.firstSoa, batch.secondSoa, results, isa);
      ASSERT_EQ(results.size(), batch.size());
      for (std::size_t i = 0; i < batch.size(); ++i) {
        SCOPED_TRACE(std::string(name(isa)) + " " + name(family) + " pair " + std::to_string(i) +
                     "\n" + pasteable(batch.first[i], batch.second[i]));
        ++pairs;
        if (!fused) {
          EXPECT_EQ(results.distanceSquared(i), reference.distanceSquared(i));
          EXPECT_EQ(results.p(i), reference.p(i));
          EXPECT_EQ(results.q(i), reference.q(i));
          EXPECT_EQ(results.errorBound(i), reference.errorBound(i));
          EXPECT_EQ(results.converged(i), reference.converged(i));
          continue;
        }
        flagDiffers += results.converged(i) != reference.converged(i);
        if (!results.converged(i) || !reference.converged(i)) continue;
        ++bothConverged;
        const double size = pairSize(batch.first[i], batch.second[i]);
        const double difference = std::fabs(results.distance(i) - reference.distance(i));
        EXPECT_LE(difference, std::max(results.errorBound(i), reference.errorBound(i)) +
                                  64 * kEpsilon * (size + reference.distance(i)));
        worstUlps = std::max(worstUlps, difference / (kEpsilon * (size + reference.distance(i))));
      }
    }
    std::printf(
        "penalty %s vs scalar: converged flag differs on %zu of %zu pairs; %zu converged "
        "on both, distances up to %.3g ulps apart\n",
        name(isa), flagDiffers, pairs, bothConverged, worstUlps);
    EXPECT_LE(flagDiffers, pairs / 50);  // measured about 1%
  }
}

// The hybrid is exact on every ISA: its answers agree with the reference to the contract's
// 1e-12 of the pair's size (in practice a few ulps: FMA rounds the closed forms differently, and
// a pair may be certified by another stage), flags exactly.
TEST(KernelDispatch, EveryIsaHybridMatchesTheScalarReference) {
  for (Isa isa : supportedIsas()) {
    if (isa == Isa::Scalar) continue;
    double worst = 0.0;
    for (auto family : kAllFamilies) {
      const PairBatch batch = makeBatch(makePairs(family, test::scaledCount(2000), 37));
      PairResults reference(batch.size()), results(batch.size());
      hybridDistances(batch.firstSoa, batch.secondSoa, reference, Isa::Scalar);
      hybridDistances(batch.firstSoa, batch.secondSoa, results, isa);
      for (std::size_t i = 0; i < batch.size(); ++i) {
        const double size = pairSize(batch.first[i], batch.second[i]);
        const double difference = std::fabs(results.distance(i) - reference.distance(i));
        worst = std::max(worst, difference / (kEpsilon * std::max(size, reference.distance(i))));
        EXPECT_LE(difference, 1e-12 * size)
            << name(isa) << " " << name(family) << " pair " << i << "\n"
            << pasteable(batch.first[i], batch.second[i]);
        EXPECT_EQ(results.intersect(i), reference.intersect(i))
            << name(isa) << " " << name(family) << " pair " << i << "\n"
            << pasteable(batch.first[i], batch.second[i]);
      }
    }
    std::printf("hybrid %s vs scalar: distances up to %.3g ulps of max(size, distance) apart\n",
                name(isa), worst);
  }
}

/// The brute force's answer for (first, second), the reference for batch-shape tests.
void expectMatchesBruteForce(const PairResults& results, std::size_t i, const Triangle& first,
                             const Triangle& second, Solver solver, Isa isa) {
  const TriangleDistanceResult exact = triangleDistanceBruteForce(first, second);
  const double size = pairSize(first, second);
  const double tolerance =
      solver == Solver::Penalty ? results.errorBound(i) + 1e-12 * size : 1e-12 * size;
  EXPECT_NEAR(results.distance(i), std::sqrt(exact.distanceSquared), tolerance)
      << name(solver) << " " << name(isa) << " pair " << i << "\n"
      << pasteable(first, second);
  if (solver != Solver::Penalty) {
    EXPECT_EQ(results.intersect(i), exact.intersect);
  }
}

// Batches of 1, 7, 8, 9, 17 and 33 pairs (partial registers on every ISA): every pair is
// computed, nothing beyond the last pair is written, and the statistics count real pairs only.
TEST(KernelDispatch, BatchesOfAnySizeWriteExactlyTheirPairs) {
  const auto pairs = makePairs(test::PairFamily::NearContact, 40, 41);
  for (const std::size_t count : {1, 7, 8, 9, 17, 33}) {
    const PairBatch batch = makeBatch({pairs.begin(), pairs.begin() + count});
    for (Solver solver : {Solver::BruteForce, Solver::Penalty, Solver::Hybrid})
      for (Isa isa : supportedIsas()) {
        SCOPED_TRACE(std::string(name(solver)) + " " + name(isa) + " count " +
                     std::to_string(count));
        // Fill the results through a larger batch, then run the smaller one over them.
        PairResults results(48);
        const PairBatch filler = makeBatch({pairs.begin(), pairs.begin() + 40});
        distances(solver, filler.firstSoa, filler.secondSoa, results, isa);
        std::vector<double> before(48);
        for (std::size_t i = 0; i < 40; ++i)
          before[i] = results.distanceSquared(i);
        const BatchStatistics statistics =
            distances(solver, batch.firstSoa, batch.secondSoa, results, isa);
        EXPECT_EQ(statistics.pairs, count);
        EXPECT_EQ(results.size(), count);
        EXPECT_LE(statistics.fallbacks, count);
        EXPECT_LE(statistics.rechecked, count);
        EXPECT_LE(statistics.unconverged, count);
        for (std::size_t i = 0; i < count; ++i)
          expectMatchesBruteForce(results, i, batch.first[i], batch.second[i], solver, isa);
        for (std::size_t i = count; i < 40; ++i)
          EXPECT_EQ(results.distanceSquared(i), before[i]) << "pair " << i << " overwritten";
      }
  }
}

// One triangle against block[begin, end) for ranges starting anywhere, ending at the block's end
// (the last register then reaches past the padded streams) or before it.
TEST(KernelDispatch, OneAgainstAnyRangeOfABlock) {
  const auto pairs = makePairs(test::PairFamily::NearContact, 19, 43);
  const PairBatch batch = makeBatch(pairs);  // 19 triangles: padded to 24
  const Triangle& one = batch.first[3];
  for (Solver solver : {Solver::BruteForce, Solver::Penalty, Solver::Hybrid})
    for (Isa isa : supportedIsas())
      for (const auto& [begin, end] : std::vector<std::pair<std::size_t, std::size_t>>{
               {0, 19}, {3, 19}, {5, 12}, {18, 19}, {11, 19}, {7, 8}, {9, 30}, {19, 19}}) {
        SCOPED_TRACE(std::string(name(solver)) + " " + name(isa) + " [" + std::to_string(begin) +
                     ", " + std::to_string(end) + ")");
        PairResults results(32);
        const BatchStatistics statistics =
            distances(solver, one, batch.secondSoa, begin, end, results, isa);
        const std::size_t expected = std::min<std::size_t>(end, 19) - std::min(begin, end);
        EXPECT_EQ(results.size(), expected);
        EXPECT_EQ(statistics.pairs, expected);
        for (std::size_t j = 0; j < results.size(); ++j)
          expectMatchesBruteForce(results, j, one, batch.second[begin + j], solver, isa);
      }
}

TEST(KernelDispatch, ResultsCapacityLimitsTheBatch) {
  const PairBatch batch = makeBatch(makePairs(test::PairFamily::Random, 20, 47));
  PairResults results(5);
  for (Solver solver : {Solver::BruteForce, Solver::Penalty, Solver::Hybrid}) {
    const BatchStatistics statistics = distances(solver, batch.firstSoa, batch.secondSoa, results);
    EXPECT_EQ(results.size(), 5u);
    EXPECT_EQ(statistics.pairs, 5u);
  }
  PairResults empty;
  EXPECT_EQ(hybridDistances(batch.firstSoa, batch.secondSoa, empty).pairs, 0u);
  EXPECT_EQ(empty.size(), 0u);
  results.reserve(64);  // keeps what it held
  EXPECT_EQ(results.size(), 5u);
  EXPECT_GE(results.capacity(), 64u);
}

TEST(KernelDispatch, UnequalBlocksPairUpToTheShorter) {
  const PairBatch a = makeBatch(makePairs(test::PairFamily::NearContact, 12, 53));
  const PairBatch b = makeBatch(makePairs(test::PairFamily::NearContact, 9, 59));
  PairResults results(16);
  EXPECT_EQ(hybridDistances(a.firstSoa, b.secondSoa, results).pairs, 9u);
  for (std::size_t i = 0; i < 9; ++i)
    expectMatchesBruteForce(results, i, a.first[i], b.second[i], Solver::Hybrid, defaultIsa());
}

}  // namespace
}  // namespace delta::kernels
