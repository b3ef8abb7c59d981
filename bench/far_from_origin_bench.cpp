// Point queries of a mesh far from the origin (georeferenced or world-frame CAD): armadillo moved
// by 10^k along (1, 1, 1), 20,000 uniform points in its box, on one thread. The tree's boxes and
// leaf triangles are single precision less the mesh box's centre, and the leaf bounds' margin
// does not grow with the offset, so the time a point should not depend on k (docs/performance.md).
//   build/bench/delta_bench_far_from_origin --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "delta/delta.h"

#include "bench_main.h"
#include "omp_threads.h"

namespace {

const std::string kArmadillo = std::string(DELTA_DATA_DIR) + "/meshes/armadillo.off";

/// Argument: the offset's decimal exponent k (0 for no offset).
void DistancesFarFromTheOrigin(benchmark::State& state) {
  if (!std::filesystem::exists(kArmadillo)) {
    state.SkipWithError("armadillo.off missing: run scripts/setup.sh");
    return;
  }
  const double offset = state.range(0) == 0 ? 0.0 : std::pow(10.0, state.range(0));
  delta::Mesh mesh = delta::io::load(kArmadillo);
  mesh.translate({offset, offset, offset});
  const delta::QueryMesh query(mesh);
  const delta::Aabb box = mesh.bounds();
  std::mt19937_64 random(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<delta::Vec3> points(20000);
  for (delta::Vec3& p : points)
    p = box.lower + delta::Vec3{unit(random) * box.extent().x, unit(random) * box.extent().y,
                                unit(random) * box.extent().z};
  const delta::bench::OmpThreads one(1);
  for (auto _ : state)
    benchmark::DoNotOptimize(delta::contactdetection::distances(query, points));
  state.counters["points_per_s"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(DistancesFarFromTheOrigin)
    ->Arg(0)
    ->Arg(6)
    ->Arg(7)
    ->Arg(8)
    ->Arg(9)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  return delta::bench::runBenchmarks(argc, argv);
}
