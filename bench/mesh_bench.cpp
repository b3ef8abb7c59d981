// Mesh set-up costs: loading a real mesh through assimp versus flattening it into the SoA the
// kernels read. DESIGN.md asks that flattening 10⁶ triangles cost well under loading them.
//   build/bench/delta_bench_mesh --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>

#include "delta/delta.h"

#include "bench_main.h"

namespace {

const std::string kElephant = std::string(DELTA_DATA_DIR) + "/meshes/refined_elephant.off";

void LoadElephant(benchmark::State& state) {
  if (!std::filesystem::exists(kElephant)) {
    state.SkipWithError("refined_elephant.off missing: run scripts/setup.sh");
    return;
  }
  std::size_t triangles = 0;
  for (auto _ : state)
    triangles = delta::io::load(kElephant).triangleCount();
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["triangles_per_s"] = benchmark::Counter(
      static_cast<double>(triangles), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(LoadElephant)->Unit(benchmark::kMillisecond);

void FlattenElephant(benchmark::State& state) {
  if (!std::filesystem::exists(kElephant)) {
    state.SkipWithError("refined_elephant.off missing: run scripts/setup.sh");
    return;
  }
  const delta::Mesh mesh = delta::io::load(kElephant);
  for (auto _ : state)
    benchmark::DoNotOptimize(delta::flatten(mesh).size());
  state.counters["triangles_per_s"] = benchmark::Counter(
      static_cast<double>(mesh.triangleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(FlattenElephant)->Unit(benchmark::kMillisecond);

// 20·4⁸ = 1,310,720 triangles: the "10⁶ triangles" of the requirement.
void FlattenIcosphere(benchmark::State& state) {
  const delta::Mesh mesh = delta::primitives::icosphere(static_cast<int>(state.range(0)));
  for (auto _ : state)
    benchmark::DoNotOptimize(delta::flatten(mesh).size());
  state.counters["triangles"] = static_cast<double>(mesh.triangleCount());
  state.counters["triangles_per_s"] = benchmark::Counter(
      static_cast<double>(mesh.triangleCount()), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(FlattenIcosphere)->Arg(4)->Arg(8)->Unit(benchmark::kMillisecond);

// Writing the icosphere to a binary STL and loading it back: load cost at 10⁶ triangles.
void LoadMillionTriangleStl(benchmark::State& state) {
  const auto path = std::filesystem::temp_directory_path() / "delta_bench_icosphere8.stl";
  delta::io::save(delta::primitives::icosphere(8), path);
  std::size_t triangles = 0;
  for (auto _ : state)
    triangles = delta::io::load(path).triangleCount();
  std::filesystem::remove(path);
  state.counters["triangles"] = static_cast<double>(triangles);
  state.counters["triangles_per_s"] = benchmark::Counter(
      static_cast<double>(triangles), benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(LoadMillionTriangleStl)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  return delta::bench::runBenchmarks(argc, argv);
}
