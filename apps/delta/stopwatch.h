#pragma once

#include <chrono>
#include <cstddef>

namespace delta::cli {

/// Wall-clock seconds since construction (or the last restart).
class Stopwatch {
 public:
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }
  double restart() {
    const double elapsed = seconds();
    start_ = std::chrono::steady_clock::now();
    return elapsed;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

/// The process's peak resident memory so far, in bytes.
std::size_t peakResidentBytes();

}  // namespace delta::cli
