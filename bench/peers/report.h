#pragma once

// What bench/peers/peers_bench.cpp reports beside Google Benchmark's own output: the peers'
// versions in the context, and the peer/Δ ratios of query time, which Google Benchmark does not
// compute, from the runs its display reporter shows.

#include <benchmark/benchmark.h>

#include <cstddef>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace delta::bench {

/// 1234567 → "1,234,567".
std::string withCommas(std::size_t value);

/// Adds the versions of the peers this program was built with to Google Benchmark's context
/// (embree_version, cgal_version, fcl_version) and names those it was built without
/// (skipped_peers: "FCL (not built with FCL)").
void addPeersToContext();

/// Google Benchmark's display reporter (the one --benchmark_format chooses, made once the flags
/// are read), recording the real time of every run it shows. The benchmarks are named
/// workload/mesh/library/threads:N; library "Delta" is the reference the others are divided by.
///
/// Threading: Google Benchmark calls it from the thread that runs the benchmarks.
class RatioReporter final : public benchmark::BenchmarkReporter {
 public:
  bool ReportContext(const Context& context) override;
  void ReportRuns(const std::vector<Run>& runs) override;
  void Finalize() override;

  /// Whether benchmarks ran (not with --benchmark_list_tests, or a filter matching nothing).
  bool ran() const noexcept { return display_ != nullptr; }
  /// Whether the display is Google Benchmark's console table (not JSON or CSV): then the ratio
  /// table goes to stdout beside it, else to stderr, so that stdout stays one JSON document.
  bool displaysConsole() const noexcept;
  /// peer/Δ query time per mesh, workload and thread count (Δ's own time in milliseconds): the
  /// median aggregate where there were repetitions, else the run's time; runs that stopped with
  /// an error are left out. Workloads without a peer (W5's grid) have no row.
  void printRatios(std::FILE* out) const;

 private:
  struct Time {
    double seconds = 0.0;  // real time of one query
    bool median = false;   // the median aggregate of the repetitions
  };
  /// The times of one mesh, workload and thread count, per library.
  struct Measured {
    std::string mesh, workload;
    int threads = 1;
    std::map<std::string, Time> byLibrary;
  };

  void record(const Run& run);

  benchmark::BenchmarkReporter* display_ = nullptr;  // made and kept by Google Benchmark
  std::vector<Measured> measured_;                   // in the order first run
  std::vector<std::string> peers_;                   // the libraries other than Δ, as met
};

}  // namespace delta::bench
