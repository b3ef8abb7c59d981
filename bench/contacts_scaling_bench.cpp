// Thread scaling of mesh–mesh contact detection: the seed paper's intra-library study (two
// colliding DEM particles, its Figure 3: "the intra-library parallelisation starts to upscale once
// the individual mesh consists of 40–80 triangles"), and the DEM case of many independent pairs
// run with the parallelism outside the library (one contacts() call per thread) or inside it.
//   build/bench/delta_bench_contacts_scaling --benchmark_repetitions=5
//   --benchmark_report_aggregates_only=true --benchmark_enable_random_interleaving=true
// (interleaving runs the 1- and 2-thread repetitions alternately, so drift hits both alike).
//
// A pair: two random convex granulates (primitives::granulate on the unit sphere, 2·points − 4
// triangles), the second rotated, moved along +x until the two just touch and then pushed
// kOverlap further: a DEM overlap of 0.5% of the diameter, the same at every resolution, so the
// box pruning leaves work only in the small contact zone. ContactsConcentric is the control
// without that: the second particle at the first's centre, the surfaces crossing all around, so
// nearly every triangle pair reaches the kernels, as in the seed's unpruned all-pairs loop.
// ε = kEpsilon, 1% of the radius, so every pair yields contacts. Rates are mesh pairs per second
// (items_per_second) and nominal triangle pairs (|first|·|second|, before pruning) per second.
// OpenMP thread counts 1, 2, 4, … up to omp_get_num_procs().
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdint>
#include <iterator>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "delta/delta.h"

#include "bench_main.h"
#include "omp_threads.h"

namespace {

using delta::Mesh;
using delta::TriangleSoA;
namespace cd = delta::contactdetection;
using delta::bench::OmpThreads;
using delta::bench::threadCounts;

constexpr double kEpsilon = 0.01;
constexpr double kOverlap = 0.01;
/// Independent particle pairs in the DEM benchmarks.
constexpr std::size_t kDemPairs = 64;
/// Triangles per mesh: granulates of (triangles + 4) / 2 hull points.
constexpr std::int64_t kTriangles[] = {20, 40, 80, 160, 320, 1280};

struct MeshPair {
  TriangleSoA first, second;
  std::size_t contacts = 0;
  double centreDistance = 0.0;
};

/// `second` (centred at the origin) moved along +x against `first` until they touch, then
/// `overlap` further. The distance between convex bodies is 1-Lipschitz in the shift, so stepping
/// back by the current minimum distance never passes the touching shift: it converges from above.
MeshPair placeAgainst(const Mesh& first, Mesh second, double overlap) {
  const TriangleSoA firstSoa = delta::flatten(first);
  double shift = first.bounds().upper.x - second.bounds().lower.x + overlap;
  for (int step = 0; step < 200; ++step) {
    const Mesh moved = Mesh(second).translate({shift, 0, 0});
    const double gap = cd::minimumDistance(firstSoa, delta::flatten(moved)).distance;
    if (gap < 1e-9) break;
    shift -= gap;
  }
  shift -= overlap;
  MeshPair pair{firstSoa, delta::flatten(second.translate({shift, 0, 0})), 0, shift};
  pair.contacts = cd::contacts(pair.first, pair.second, kEpsilon).size();
  return pair;
}

/// Where the second particle of a pair sits.
enum class Placement {
  Touching,    ///< against the first, overlapping by kOverlap: contacts in one small zone
  Concentric,  ///< at the first's centre: the surfaces cross all around, work on every triangle
};

/// Pair `index` of meshes with `triangles` triangles: its own seeds and rotation.
MeshPair makePair(std::int64_t triangles, std::uint64_t index, Placement placement) {
  const int points = static_cast<int>((triangles + 4) / 2);
  const Mesh first = delta::primitives::granulate(2 * index + 1, {1, 1, 1}, points);
  Mesh second = delta::primitives::granulate(2 * index + 2, {1, 1, 1}, points);
  second.rotate({1, 2, 3}, 0.7 + 0.1 * static_cast<double>(index));
  if (placement == Placement::Touching) return placeAgainst(first, std::move(second), kOverlap);
  MeshPair pair{delta::flatten(first), delta::flatten(second), 0, 0.0};
  pair.contacts = cd::contacts(pair.first, pair.second, kEpsilon).size();
  return pair;
}

/// The first `count` pairs of meshes with `triangles` triangles, built once per process.
const std::vector<MeshPair>& pairs(std::int64_t triangles, std::size_t count,
                                   Placement placement = Placement::Touching) {
  static std::map<std::tuple<std::int64_t, std::size_t, Placement>, std::vector<MeshPair>> cache;
  std::vector<MeshPair>& set = cache[{triangles, count, placement}];
  for (std::size_t i = set.size(); i < count; ++i)
    set.push_back(makePair(triangles, i, placement));
  return set;
}

/// Whether every mesh of `set` has `triangles` triangles (skips the benchmark when not).
bool hasSize(benchmark::State& state, const std::vector<MeshPair>& set, std::int64_t triangles) {
  for (const MeshPair& pair : set)
    if (pair.first.size() != static_cast<std::size_t>(triangles) ||
        pair.second.size() != static_cast<std::size_t>(triangles)) {
      state.SkipWithError("a granulate lost hull points");
      return false;
    }
  return true;
}

/// Sets the rate counters, after checking that the threads found the contacts of the set-up.
void setRates(benchmark::State& state, const std::vector<MeshPair>& set, std::size_t contacts) {
  std::size_t expected = 0;
  for (const MeshPair& pair : set)
    expected += pair.contacts;
  if (contacts != expected) state.SkipWithError("contact count changed with the thread count");
  double trianglePairs = 0.0;
  for (const MeshPair& pair : set)
    trianglePairs += static_cast<double>(pair.first.size() * pair.second.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(set.size()));
  state.counters["triangle_pairs_per_s"] =
      benchmark::Counter(trianglePairs, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["contacts_per_pair"] =
      static_cast<double>(contacts) / static_cast<double>(set.size());
}

/// One pair of particles, contacts() parallel over the first mesh's triangles.
void Contacts(benchmark::State& state, Placement placement) {
  const std::vector<MeshPair>& set = pairs(state.range(0), 1, placement);
  if (!hasSize(state, set, state.range(0))) return;
  const OmpThreads threads(static_cast<int>(state.range(1)));
  std::size_t contacts = 0;
  for (auto _ : state) {
    const std::vector<delta::ContactPoint> found =
        cd::contacts(set.front().first, set.front().second, kEpsilon);
    contacts = found.size();
    benchmark::DoNotOptimize(found.data());
  }
  setRates(state, set, contacts);
  state.counters["centre_distance"] = set.front().centreDistance;
}

/// kDemPairs independent pairs, parallel over the pairs: each contacts() call runs serially on
/// its thread (parallelFor runs serially inside a parallel region).
void DemOuter(benchmark::State& state) {
  const std::vector<MeshPair>& set = pairs(state.range(0), kDemPairs);
  if (!hasSize(state, set, state.range(0))) return;
  const OmpThreads threads(static_cast<int>(state.range(1)));
  std::vector<std::size_t> found(set.size());
  for (auto _ : state) {
    delta::parallelFor(0, set.size(), 1, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i)
        found[i] = cd::contacts(set[i].first, set[i].second, kEpsilon).size();
    });
    benchmark::DoNotOptimize(found.data());
  }
  std::size_t contacts = 0;
  for (std::size_t count : found)
    contacts += count;
  setRates(state, set, contacts);
}

/// The same pairs one after the other, each contacts() call parallel inside.
void DemInner(benchmark::State& state) {
  const std::vector<MeshPair>& set = pairs(state.range(0), kDemPairs);
  if (!hasSize(state, set, state.range(0))) return;
  const OmpThreads threads(static_cast<int>(state.range(1)));
  std::vector<std::size_t> found(set.size());
  for (auto _ : state) {
    for (std::size_t i = 0; i < set.size(); ++i)
      found[i] = cd::contacts(set[i].first, set[i].second, kEpsilon).size();
    benchmark::DoNotOptimize(found.data());
  }
  std::size_t contacts = 0;
  for (std::size_t count : found)
    contacts += count;
  setRates(state, set, contacts);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("omp_num_procs", std::to_string(omp_get_num_procs()));
  benchmark::AddCustomContext("epsilon", std::to_string(kEpsilon));
  const std::vector<std::int64_t> sizes(std::begin(kTriangles), std::end(kTriangles));
  const std::vector<std::int64_t> threads = threadCounts();
  const auto overSizesAndThreads = [&](benchmark::internal::Benchmark* family) {
    family->ArgsProduct({sizes, threads})
        ->ArgNames({"triangles", "omp_threads"})
        ->UseRealTime()
        ->Unit(benchmark::kMicrosecond);
  };
  overSizesAndThreads(benchmark::RegisterBenchmark("Contacts", Contacts, Placement::Touching));
  overSizesAndThreads(
      benchmark::RegisterBenchmark("ContactsConcentric", Contacts, Placement::Concentric));
  overSizesAndThreads(benchmark::RegisterBenchmark("DemOuter", DemOuter));
  overSizesAndThreads(benchmark::RegisterBenchmark("DemInner", DemInner));
  return delta::bench::runBenchmarks(argc, argv);
}
