// Triangle–triangle solvers side by side on the same pairs: the scalar brute force, the penalty
// Newton and the hybrid on every instruction set this CPU has, and FCL's TriangleDistance (PQP's
// TriDist) as a peer when FCL is installed. Single thread; pairs per second.
//   build/bench/delta_bench_kernels --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true
//
// The pairs are DEM-like: 3 in 4 are near contacts (similar sizes, separated by a plane, gap 0–0.2
// of the size), 1 in 4 far apart (3–50 sizes), drawn by the kernel tests' generator.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <string>
#include <vector>

#include "delta/delta.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/kernels/triangle_triangle.h"

#include "../tests/kernels/triangle_pairs.h"
#include "bench_main.h"

#if defined(DELTA_HAVE_FCL)
#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>
#endif

namespace {

using delta::Triangle;
using delta::kernels::Isa;
using delta::kernels::PairResults;
using delta::kernels::Solver;

constexpr std::size_t kPairs = 4096;

struct PairSet {
  std::vector<Triangle> first, second;
  delta::TriangleSoA firstSoa, secondSoa;
};

delta::TriangleSoA flattenTriangles(const std::vector<Triangle>& triangles) {
  std::vector<delta::Vec3> vertices;
  std::vector<delta::TriangleIndices> indices;
  for (const Triangle& t : triangles) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), {t.a, t.b, t.c});
    indices.push_back({base, base + 1, base + 2});
  }
  return delta::flatten(delta::Mesh(std::move(vertices), std::move(indices)));
}

const PairSet& demPairs() {
  static const PairSet set = [] {
    using delta::test::PairFamily;
    const auto near = delta::test::makePairs(PairFamily::NearContact, kPairs, 2024);
    const auto far = delta::test::makePairs(PairFamily::Far, kPairs / 4, 2024);
    PairSet s;
    for (std::size_t i = 0; i < kPairs; ++i) {
      const auto& pair = i % 4 == 3 ? far[i / 4] : near[i];
      s.first.push_back(pair.first);
      s.second.push_back(pair.second);
    }
    s.firstSoa = flattenTriangles(s.first);
    s.secondSoa = flattenTriangles(s.second);
    return s;
  }();
  return set;
}

void setRate(benchmark::State& state, std::size_t pairs) {
  state.counters["pairs_per_s"] =
      benchmark::Counter(static_cast<double>(pairs), benchmark::Counter::kIsIterationInvariantRate);
}

void BruteForce(benchmark::State& state) {
  const PairSet& set = demPairs();
  PairResults results(kPairs);
  for (auto _ : state) {
    delta::kernels::bruteForceDistances(set.firstSoa, set.secondSoa, results);
    benchmark::DoNotOptimize(results.distanceSquaredData());
    benchmark::ClobberMemory();
  }
  setRate(state, kPairs);
}

void Batch(benchmark::State& state, Solver solver, Isa isa) {
  const PairSet& set = demPairs();
  PairResults results(kPairs);
  delta::kernels::BatchStatistics statistics;
  std::size_t fallbacks = 0, rechecked = 0, unconverged = 0, calls = 0;
  for (auto _ : state) {
    statistics = delta::kernels::distances(solver, set.firstSoa, set.secondSoa, results, isa);
    benchmark::DoNotOptimize(results.distanceSquaredData());
    benchmark::ClobberMemory();
    fallbacks += statistics.fallbacks;
    rechecked += statistics.rechecked;
    unconverged += statistics.unconverged;
    ++calls;
  }
  setRate(state, kPairs);
  const double pairs = static_cast<double>(calls * kPairs);
  if (solver == Solver::Hybrid) {
    state.counters["fallback_rate"] = static_cast<double>(fallbacks) / pairs;
    state.counters["recheck_rate"] = static_cast<double>(rechecked) / pairs;
  }
  if (solver == Solver::Penalty)
    state.counters["unconverged_rate"] = static_cast<double>(unconverged) / pairs;
}

/// Pairs (one, block[j]): the query layer's shape, one triangle against a leaf's triangles.
void BatchOneAgainstBlock(benchmark::State& state, Solver solver, Isa isa) {
  const PairSet& set = demPairs();
  PairResults results(64);
  for (auto _ : state) {
    for (std::size_t i = 0; i < kPairs; i += 64) {
      delta::kernels::distances(solver, set.first[i], set.secondSoa, i, i + 64, results, isa);
      benchmark::DoNotOptimize(results.distanceSquaredData());
      benchmark::ClobberMemory();
    }
  }
  setRate(state, kPairs);
}

#if defined(DELTA_HAVE_FCL)
void FclTriDist(benchmark::State& state) {
  const PairSet& set = demPairs();
  using V = fcl::Vector3<double>;
  std::vector<std::array<V, 3>> first, second;
  for (std::size_t i = 0; i < kPairs; ++i) {
    const Triangle& a = set.first[i];
    const Triangle& b = set.second[i];
    first.push_back({V(a.a.x, a.a.y, a.a.z), V(a.b.x, a.b.y, a.b.z), V(a.c.x, a.c.y, a.c.z)});
    second.push_back({V(b.a.x, b.a.y, b.a.z), V(b.b.x, b.b.y, b.b.z), V(b.c.x, b.c.y, b.c.z)});
  }
  std::vector<double> distances(kPairs);
  for (auto _ : state) {
    V p, q;
    for (std::size_t i = 0; i < kPairs; ++i)
      distances[i] = fcl::detail::TriangleDistance<double>::triDistance(first[i].data(),
                                                                        second[i].data(), p, q);
    benchmark::DoNotOptimize(distances.data());
    benchmark::ClobberMemory();
  }
  setRate(state, kPairs);
}
#endif

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("delta_default_isa",
                              delta::kernels::name(delta::kernels::defaultIsa()));
  benchmark::AddCustomContext("penalty_iterations",
                              std::to_string(delta::kernels::kPenaltyIterations));
  benchmark::AddCustomContext("hybrid_iterations",
                              std::to_string(delta::kernels::kHybridIterations));
  benchmark::RegisterBenchmark("BruteForce/scalar", BruteForce)->Unit(benchmark::kMicrosecond);
#if defined(DELTA_HAVE_FCL)
  benchmark::AddCustomContext("fcl", "TriangleDistance<double>::triDistance");
  benchmark::RegisterBenchmark("FclTriDist", FclTriDist)->Unit(benchmark::kMicrosecond);
#endif
  for (Solver solver : {Solver::Penalty, Solver::Hybrid})
    for (Isa isa : delta::kernels::supportedIsas()) {
      const std::string label =
          std::string(delta::kernels::name(solver)) + "/" + delta::kernels::name(isa);
      benchmark::RegisterBenchmark(("Pairs/" + label).c_str(), Batch, solver, isa)
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("OneAgainstBlock/" + label).c_str(), BatchOneAgainstBlock,
                                   solver, isa)
          ->Unit(benchmark::kMicrosecond);
    }
  return delta::bench::runBenchmarks(argc, argv);
}
