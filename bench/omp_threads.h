#pragma once

// OpenMP thread counts for the Google Benchmark programs in bench/: the counts to run each case
// on, and a guard that sets the count for one benchmark.

#include <omp.h>

#include <cstdint>
#include <vector>

namespace delta::bench {

/// Sets the OpenMP thread count for one benchmark and restores the previous one after it.
class OmpThreads {
 public:
  explicit OmpThreads(int threads) : previous_(omp_get_max_threads()) {
    omp_set_num_threads(threads);
  }
  ~OmpThreads() { omp_set_num_threads(previous_); }
  OmpThreads(const OmpThreads&) = delete;
  OmpThreads& operator=(const OmpThreads&) = delete;

 private:
  int previous_;
};

/// 1, 2, 4, … OpenMP threads, up to the processors this process may use (at least 1 and 2).
inline std::vector<std::int64_t> threadCounts() {
  std::vector<std::int64_t> counts;
  for (int threads = 1; threads <= omp_get_num_procs(); threads *= 2)
    counts.push_back(threads);
  if (counts.size() < 2) counts.push_back(2);
  return counts;
}

}  // namespace delta::bench
