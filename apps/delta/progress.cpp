#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace delta::cli {

Progress::Progress(std::string label, std::size_t total, bool enabled)
    : label_(std::move(label)), total_(total), enabled_(enabled) {}

Progress::~Progress() {
  if (drawn_) std::fprintf(stderr, "\r\033[K");  // leave the terminal as it was
}

void Progress::update(std::size_t done) {
  if (!enabled_) return;
  const double elapsed = clock_.seconds();
  if (elapsed - lastDraw_ < 0.2 && done < total_) return;
  lastDraw_ = elapsed;
  const double rate = elapsed > 0.0 ? static_cast<double>(done) / elapsed : 0.0;
  const double eta = rate > 0.0 ? static_cast<double>(total_ - done) / rate : 0.0;
  std::fprintf(stderr, "\r\033[K%s: %zu/%zu (%.3g/s, ETA %.1f s)", label_.c_str(), done, total_,
               rate, eta);
  std::fflush(stderr);
  drawn_ = true;
}

bool showProgress(bool quiet) {
  return !quiet && isatty(STDOUT_FILENO) && isatty(STDERR_FILENO);
}

}  // namespace delta::cli
