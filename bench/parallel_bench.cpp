// Δ's thread pool (core/parallel.h) on loops as short as a DEM step's: how long a parallel loop
// takes after some serial work on the calling thread, on one and two threads. The loop's 64
// chunks each spin for 1/64 of its work; the serial work spins before it, outside the timing.
// Where a worker sleeps too deeply between loops, two threads take as long as one.
//
//   build/bench/delta_bench_parallel --benchmark_repetitions=3
//
// Arguments: serial µs before the loop, the loop's work in µs, threads.

#include <benchmark/benchmark.h>

#include <chrono>
#include <cstddef>
#include <cstdint>

#include "delta/core/parallel.h"

#include "bench_main.h"
#include "omp_threads.h"

namespace delta::bench {
namespace {

using Clock = std::chrono::steady_clock;

void spinFor(double microseconds) {
  const auto until = Clock::now() + std::chrono::duration<double, std::micro>(microseconds);
  while (Clock::now() < until) {
  }
}

void LoopAfterSerialWork(benchmark::State& state) {
  const auto serial = static_cast<double>(state.range(0));
  const auto work = static_cast<double>(state.range(1));
  const OmpThreads threads(static_cast<int>(state.range(2)));
  constexpr std::size_t kChunks = 64;
  for (auto _ : state) {
    state.PauseTiming();
    spinFor(serial);
    state.ResumeTiming();
    parallelFor(0, kChunks, 1, [work](std::size_t begin, std::size_t end) {
      for (std::size_t chunk = begin; chunk < end; ++chunk)
        spinFor(work / kChunks);
    });
  }
}

void arguments(benchmark::internal::Benchmark* benchmark) {
  benchmark->ArgNames({"serial_us", "work_us", "threads"});
  for (const std::int64_t serial : {5, 20, 100})
    for (const std::int64_t work : {50, 200})
      for (const std::int64_t threads : {1, 2})
        benchmark->Args({serial, work, threads});
}

BENCHMARK(LoopAfterSerialWork)->Apply(arguments)->Unit(benchmark::kMicrosecond)->UseRealTime();

}  // namespace
}  // namespace delta::bench

int main(int argc, char** argv) {
  return delta::bench::runBenchmarks(argc, argv);
}
