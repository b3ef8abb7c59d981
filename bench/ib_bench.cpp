// Immersed boundaries (issue 7): ib::AdaptiveGrid refined around armadillo (52k triangles) and
// fandisk (13k), levels 6 and 7, on 1, 2, … OpenMP threads side by side.
//   build/bench/delta_bench_ib --benchmark_repetitions=3 --benchmark_report_aggregates_only=true
//   build/bench/delta_bench_ib --benchmark_filter='GridMove/armadillo'
//
// GridBuild: one iteration builds the grid (signed distances) from the prepared boundary.
// GridMove: the grid is built once, outside the timing; one iteration moves the boundary by a
// time step (bench/boundary_step.h: turned about its box centre and moved so that its furthest
// vertex moves a fifth of the finest cell's diagonal) onward and updates the grid, after three
// untimed steps, so that the grid's distances date from several poses as in a running simulation
// (the step's motion is computed outside the timing).
//
// Counters: vertices and leaves of the grid; queries (vertex distances computed per build or
// move); queries_per_s, over the whole build or move; queries_per_s_in_delta, over the time inside
// Δ's distance queries; share_in_delta, that time over the whole (GridStatistics::querySeconds /
// GridStatistics::seconds, summed over the iterations).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "delta/delta.h"

#include "bench_main.h"
#include "boundary_step.h"
#include "omp_threads.h"

namespace {

using delta::QueryMesh;
using delta::RigidTransform;
using delta::bench::OmpThreads;
using delta::bench::threadCounts;
namespace ib = delta::ib;

/// The motion of a step, in finest-cell diagonals of the furthest vertex.
constexpr double kStepInCells = 0.2;

/// The prepared boundary `name` (from DELTA_DATA_DIR/meshes), once per process; null (and the
/// benchmark skipped) when the file is missing.
const QueryMesh* boundary(benchmark::State& state, const std::string& name) {
  static std::map<std::string, std::unique_ptr<QueryMesh>> cache;
  const auto found = cache.find(name);
  if (found != cache.end()) return found->second.get();
  const std::filesystem::path path = std::filesystem::path(DELTA_DATA_DIR) / "meshes" / name;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError((name + " missing: run scripts/setup.sh").c_str());
    return nullptr;
  }
  return cache.emplace(name, std::make_unique<QueryMesh>(delta::io::load(path)))
      .first->second.get();
}

/// The counters, with the size of `built`, the grid as built (before any move).
void setCounters(benchmark::State& state, const ib::GridStatistics& totals,
                 const ib::AdaptiveGrid& built) {
  const auto iterations = static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
  state.counters["vertices"] = static_cast<double>(built.vertexCount());
  state.counters["leaves"] = static_cast<double>(built.leafCount());
  const auto queries = static_cast<double>(totals.queries);
  state.counters["queries"] = queries / iterations;
  state.counters["queries_per_s"] = benchmark::Counter(queries, benchmark::Counter::kIsRate);
  state.counters["queries_per_s_in_delta"] = queries / totals.querySeconds;
  state.counters["share_in_delta"] = totals.querySeconds / totals.seconds;
}

void GridBuild(benchmark::State& state, const std::string& mesh) {
  const QueryMesh* prepared = boundary(state, mesh);
  if (!prepared) return;
  const OmpThreads threads(static_cast<int>(state.range(1)));
  const ib::GridOptions options{.levels = static_cast<int>(state.range(0))};
  std::unique_ptr<ib::AdaptiveGrid> grid;
  ib::GridStatistics totals;
  for (auto _ : state) {
    grid = std::make_unique<ib::AdaptiveGrid>(*prepared, options);
    totals += grid->statistics();
  }
  setCounters(state, totals, *grid);
}

void GridMove(benchmark::State& state, const std::string& mesh) {
  const QueryMesh* prepared = boundary(state, mesh);
  if (!prepared) return;
  const OmpThreads threads(static_cast<int>(state.range(1)));
  const int levels = static_cast<int>(state.range(0));
  const ib::AdaptiveGrid built(*prepared, {.levels = levels});
  ib::AdaptiveGrid grid = built;
  const double step = kStepInCells * grid.cellDiagonal(levels);
  // Onward, a step an iteration, as a body carried by a flow moves; a few steps first, so that
  // the timed moves start from a grid whose distances date from several poses.
  for (int warmUp = 0; warmUp < 3; ++warmUp)
    grid.moveBoundary(delta::bench::boundaryStep(grid.boundary(), step));
  ib::GridStatistics totals;
  for (auto _ : state) {
    state.PauseTiming();
    const RigidTransform motion = delta::bench::boundaryStep(grid.boundary(), step);
    state.ResumeTiming();
    totals += grid.moveBoundary(motion);
  }
  setCounters(state, totals, built);
  state.counters["step"] = step;
}

/// A benchmark function over a mesh file, and the name it is registered under.
struct Family {
  const char* name;
  void (*function)(benchmark::State&, const std::string&);
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("omp_num_procs", std::to_string(omp_get_num_procs()));
  const std::vector<std::int64_t> threads = threadCounts();
  for (const char* mesh : {"armadillo", "fandisk"}) {
    const std::string file = std::string(mesh) + ".off";
    for (const auto& [name, function] :
         {Family{"GridBuild/", GridBuild}, Family{"GridMove/", GridMove}})
      benchmark::RegisterBenchmark((name + std::string(mesh)).c_str(), function, file)
          ->ArgsProduct({{6, 7}, threads})
          ->ArgNames({"levels", "omp_threads"})
          ->UseRealTime()
          ->Unit(benchmark::kMillisecond);
  }
  return delta::bench::runBenchmarks(argc, argv);
}
