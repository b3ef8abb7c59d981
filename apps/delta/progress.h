#pragma once

#include <cstddef>
#include <string>

#include "stopwatch.h"

namespace delta::cli {

/// A progress line for long work: "\r<label>: done/total (rate/s, ETA s)" on stderr, redrawn at
/// most five times a second, and cleared at the end. Silent when `enabled` is false — the
/// commands pass false for --quiet, --json, or a stdout that is not a terminal (see
/// showProgress()).
///
/// Threading: one line per command; call from the thread that runs the command.
class Progress {
 public:
  Progress(std::string label, std::size_t total, bool enabled);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(std::size_t done);

 private:
  std::string label_;
  std::size_t total_;
  bool enabled_;
  bool drawn_ = false;
  Stopwatch clock_;
  double lastDraw_ = 0.0;
};

/// Whether a command shows progress: not when asked to be quiet, and only when stdout and stderr
/// are terminals.
bool showProgress(bool quiet);

}  // namespace delta::cli
