#pragma once

// The end of every Google Benchmark program's main in bench/: Δ's version and commit in the
// report's context, Google Benchmark's flags read (an unknown argument is an error, not a
// silently ignored typo), the registered benchmarks run.

#include <benchmark/benchmark.h>

#include "delta/core/version.h"

namespace delta::bench {

/// Adds Δ's version and git commit to the context, reads the flags and runs the benchmarks
/// registered so far, shown by `display` (null: Google Benchmark's own display reporter, the one
/// --benchmark_format chooses); returns main's exit status (1 for an unrecognised argument).
inline int runBenchmarks(int argc, char** argv, benchmark::BenchmarkReporter* display = nullptr) {
  benchmark::AddCustomContext("delta_version", version());
  benchmark::AddCustomContext("delta_git_commit", gitCommit());
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks(display);
  benchmark::Shutdown();
  return 0;
}

}  // namespace delta::bench
