#pragma once

#include <string>
#include <vector>

#include "delta/dem/world.h"

namespace delta::cli {

/// What makes a `delta dem` run's results doubtful without stopping it, said once each, as soon
/// as it is seen: on stderr ("delta: warning: …") and in the summary (text, and the JSON's
/// "warnings" array). A state that stops being finite, or motion the contact shell cannot
/// catch, stops the run instead (dem::World::step throws).
///
/// Threading: one object per run, used from one thread.
class DemWarnings {
 public:
  /// `print`: also write each warning to stderr when it is found (rank 0 of a distributed run).
  explicit DemWarnings(bool print) : print_(print) {}

  /// Before the first step: a time step above the one dem::World::suggestedTimeStep gives (a
  /// contact resolved in fewer steps than the law needs: energy drifts, states may blow up).
  void atStart(const dem::World& world);
  /// After the first step, with its statistics: contact points whose surfaces interpenetrate,
  /// which means particles placed overlapping (the law's overlap rule pushes them apart with
  /// energy from nothing).
  void afterFirstStep(const dem::StepStatistics& statistics);

  const std::vector<std::string>& all() const noexcept { return warnings_; }

 private:
  void warn(std::string text);

  bool print_ = true;
  std::vector<std::string> warnings_;
};

}  // namespace delta::cli
