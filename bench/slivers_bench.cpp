// Point queries among long slivers, as CAD exports a cylinder's caps (a fan of triangles from the
// cap's centre to its rim), on one thread, 2,000 points:
//  - FanOfSlivers/n: a disc of radius 1 triangulated as a fan of n slivers, points 0.3 above it
//    uniform over [−0.5, 0.5]²;
//  - CylinderOfSegments/n: primitives::cylinder(1, 1, n), points uniform in [−0.3, 0.3]³ inside;
//  - NearTheCentre/n: the fan, points 10⁻⁹ above it at 10⁻⁶ to 10⁻² from its centre;
//  - BoxOnTheCap/n: contacts (QueryMesh form, ε = 10⁻⁶, overlaps marked) of a box 10⁻³ wide
//    resting 10⁻¹² above the centre of primitives::cylinder(1, 1, n)'s cap.
// Every leaf of a fan reaches from the centre to the rim: its box, and a disc about its plane's
// normal, come as close as the plane wherever a point's foot lies in the box; the leaves' rods
// along their slivers do not (docs/performance.md, "Leaf cylinders along slivers"), but near the
// centre a point lay within every rod, and the leaves' cones now keep it out ("Cones for a fan's
// wedges").
//   build/bench/delta_bench_slivers --benchmark_repetitions=3
//       --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "delta/delta.h"

#include "bench_main.h"
#include "omp_threads.h"

namespace {

constexpr std::size_t kPoints = 2000;

delta::Mesh fan(int n) {
  std::vector<delta::Vec3> vertices{{0.0, 0.0, 0.0}};
  std::vector<delta::TriangleIndices> triangles;
  for (int i = 0; i < n; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / n;
    vertices.push_back({std::cos(angle), std::sin(angle), 0.0});
    triangles.push_back(
        {0u, static_cast<std::uint32_t>(1 + i), static_cast<std::uint32_t>(1 + (i + 1) % n)});
  }
  return delta::Mesh(std::move(vertices), std::move(triangles));
}

void run(benchmark::State& state, const delta::Mesh& mesh, const std::vector<delta::Vec3>& points) {
  const delta::QueryMesh query(mesh);
  const delta::bench::OmpThreads one(1);
  for (auto _ : state)
    benchmark::DoNotOptimize(delta::contactdetection::distances(query, points));
  state.counters["points_per_s"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void FanOfSlivers(benchmark::State& state) {
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<delta::Vec3> points(kPoints);
  for (delta::Vec3& p : points)
    p = {unit(random), unit(random), 0.3};
  run(state, fan(static_cast<int>(state.range(0))), points);
}

void CylinderOfSegments(benchmark::State& state) {
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> unit(-0.3, 0.3);
  std::vector<delta::Vec3> points(kPoints);
  for (delta::Vec3& p : points)
    p = {unit(random), unit(random), unit(random)};
  run(state, delta::primitives::cylinder(1.0, 1.0, static_cast<int>(state.range(0))), points);
}

void NearTheCentre(benchmark::State& state) {
  std::mt19937_64 random(1);
  std::uniform_real_distribution<double> exponent(-6.0, -2.0), angle(0.0, 2 * std::numbers::pi);
  std::vector<delta::Vec3> points(kPoints);
  for (delta::Vec3& p : points) {
    const double r = std::pow(10.0, exponent(random)), a = angle(random);
    p = {r * std::cos(a), r * std::sin(a), 1e-9};
  }
  run(state, fan(static_cast<int>(state.range(0))), points);
}

void BoxOnTheCap(benchmark::State& state) {
  const delta::QueryMesh cylinder(
      delta::primitives::cylinder(1.0, 1.0, static_cast<int>(state.range(0))));
  const delta::QueryMesh box(
      delta::primitives::box({1e-3, 1e-3, 1e-3}, {0, 0, 0.5 + 0.5e-3 + 1e-12}));
  const delta::bench::OmpThreads one(1);
  std::size_t found = 0;
  for (auto _ : state) {
    const auto contacts = delta::contactdetection::contacts(cylinder, box, 1e-6);
    found = contacts.size();
    benchmark::DoNotOptimize(contacts.data());
  }
  state.counters["contacts"] = static_cast<double>(found);
}

BENCHMARK(FanOfSlivers)
    ->Arg(1024)
    ->Arg(16384)
    ->Arg(65536)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(CylinderOfSegments)
    ->Arg(1024)
    ->Arg(16384)
    ->Arg(65536)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(NearTheCentre)->Arg(16384)->Arg(65536)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BoxOnTheCap)->Arg(2000)->Arg(8000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
  return delta::bench::runBenchmarks(argc, argv);
}
