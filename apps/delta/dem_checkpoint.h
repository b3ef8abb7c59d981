#pragma once

#include <csignal>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/dem/world.h"

#include "dem_output.h"

/// `delta dem --checkpoint-every N`, `--restart FILE`, and stopping on SIGINT or SIGTERM with a
/// checkpoint (dem/checkpoint.h has the file's format).
namespace delta::cli {

/// The checkpoint's name in the --out folder.
inline constexpr const char* kCheckpointName = "checkpoint.delta";

/// What `delta dem` keeps in a checkpoint's note besides the World: what the run was, so that
/// --restart continues it without its options.
///
/// Threading: a value type.
struct DemRunNote {
  std::string scenario;   ///< the scenario's name (two-particles, settle, hopper, or a config's)
  std::size_t steps = 0;  ///< the run's total step count
  std::size_t outputEvery = 1;
  std::string frames = "state";  ///< --frames
  std::size_t checkpointEvery = 0;
  std::vector<double> frameTimes;  ///< the frames written so far (--out), their simulated times
  /// 16 hex digits drawn when the run began, kept by its restarts, and written beside its output
  /// (kRunMarkerName): a restart continues a folder's series only where the two agree. Empty in
  /// the notes of Δ versions that had none.
  std::string run;

  /// As text: one `key = value` a line, the times at full precision (%.17g).
  std::string text() const;
  /// Reads text(); throws delta::Error naming `origin` for a note that is not one.
  static DemRunNote parse(const std::string& text, const std::string& origin);
};

/// The file in a run's --out folder that names the run its output belongs to (DemRunNote::run).
inline constexpr const char* kRunMarkerName = ".delta.run";

/// A new run's identity: 16 hex digits from std::random_device and the clock.
std::string newRunId();

/// The run `directory`'s marker names (kRunMarkerName), "" where it has none or it is not one.
std::string runMarkerOf(const std::filesystem::path& directory);

/// Writes `directory`'s marker for `run` (atomically); nothing for an empty `run`.
void writeRunMarker(const std::filesystem::path& directory, const std::string& run);

/// Thrown out of a run stopped by SIGINT or SIGTERM once its checkpoint is written and its files
/// are closed; `delta dem` then exits with 128 + the signal (130, 143).
struct StoppedBySignal {
  int signal = 0;
  std::size_t step = 0;  ///< the step it stopped after
  bool report = true;    ///< this process says so (rank 0 of a distributed run)
};

/// A run's checkpoints: every N steps (N > 0) and at its end into `directory`/checkpoint.delta,
/// and when SIGINT or SIGTERM arrive (handlers set while this object lives: the step under way
/// finishes first). Without a directory, a signal stops the run without a checkpoint.
///
/// Threading: one object per run, used from the thread that steps the World.
class DemCheckpoints {
 public:
  /// Installs the handlers (the previous ones come back on destruction).
  DemCheckpoints(std::filesystem::path directory, std::size_t every, DemRunNote note);
  ~DemCheckpoints();
  DemCheckpoints(const DemCheckpoints&) = delete;
  DemCheckpoints& operator=(const DemCheckpoints&) = delete;

  /// After a step: writes the checkpoint when the world's step count is a multiple of N;
  /// returns the signal that asks the run to stop (0: none).
  int afterStep(const dem::World& world, const DemOutput* output);
  /// Whether a checkpoint is due after step `step` (a multiple of N).
  bool due(std::size_t step) const noexcept { return every_ > 0 && step % every_ == 0; }
  /// The signal that asked this process to stop (0: none).
  int pendingSignal() const noexcept;
  /// Writes the checkpoint now (at the end of a run, or when stopped) unless it was written at
  /// this step; nothing without a directory.
  void write(const dem::World& world, const DemOutput* output);
  /// Seconds spent writing checkpoints, how many were written and the bytes of the last.
  double seconds() const noexcept { return seconds_; }
  std::size_t written() const noexcept { return written_; }
  std::size_t bytes() const noexcept { return bytes_; }
  std::filesystem::path path() const { return directory_ / kCheckpointName; }
  bool enabled() const noexcept { return !directory_.empty(); }
  std::size_t every() const noexcept { return every_; }

 private:
  std::filesystem::path directory_;
  std::size_t every_ = 0;
  DemRunNote note_;
  std::size_t lastStep_ = static_cast<std::size_t>(-1);
  double seconds_ = 0.0;
  std::size_t written_ = 0;
  std::size_t bytes_ = 0;
  struct sigaction previousInterrupt_ {};
  struct sigaction previousTerminate_ {};
  struct sigaction previousHangUp_ {};
};

}  // namespace delta::cli
