#pragma once

#include <atomic>
#include <filesystem>
#include <string>
#include <vector>

/// One run at a time in an --out folder, and no silent mixing with an earlier run's files.
namespace delta::cli {

/// The name of the lock file a run holds in its --out folder.
inline constexpr const char* kRunLockName = ".delta.lock";

/// Holds an --out folder for one run: DIR/.delta.lock, locked with flock(2) and holding
/// "PID HOST COMMAND". The kernel drops the lock when the process ends, however it ends
/// (kill -9 included), so a lock file left by a dead run is taken over, never trusted; its PID
/// is for the message only.
///
/// Threading: one object per run; release() may be called from a signal handler.
class RunLock {
 public:
  /// Locks `directory` (which must exist) for `command` ("delta dem"). Throws delta::Error
  /// "--out 'DIR' is in use by delta dem, pid N on HOST" when another process holds it, or naming
  /// the lock file and the reason when it cannot be made. A lock file left by a run that has
  /// ended is taken over: note() then says so.
  RunLock(const std::filesystem::path& directory, const std::string& command);
  /// release().
  ~RunLock();
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

  /// Removes the lock file and unlocks; idempotent. Async-signal-safe (unlink and close only),
  /// so a SIGINT/SIGTERM handler may call it before it ends the process; never throws.
  void release() noexcept;

  /// Empty, or a line about a lock file of an ended run that was taken over.
  const std::string& note() const noexcept { return note_; }
  const std::filesystem::path& path() const noexcept { return path_; }

 private:
  std::filesystem::path path_;
  std::string pathText_;  ///< path_ as a C string, made before any signal can ask for it
  std::atomic<int> descriptor_{-1};
  std::string note_;
};

/// What a run does with an --out folder that holds an earlier run's output.
enum class EarlierOutput {
  Refuse,     ///< throw (the default)
  Overwrite,  ///< remove the earlier run's files first (--overwrite)
  Continue,   ///< leave them: the run continues that one (--restart)
};

/// The files in `directory` that a `delta dem --out` run writes (log.csv, the .pvd series and
/// their frames, shape_K.vtp, obstacles.vtp, checkpoint.delta, and temporary files that a run
/// killed while writing left: io/atomic_file.h), sorted; not the lock file and nothing else. Throws
/// delta::Error naming the folder when it cannot be listed.
std::vector<std::filesystem::path> demOutputFiles(const std::filesystem::path& directory);

/// Readies `directory` (held with a RunLock) for a run: where demOutputFiles is not empty,
/// EarlierOutput::Refuse throws delta::Error "--out 'DIR' holds the output of an earlier run
/// (NAME, …): --overwrite replaces it, --restart continues it", Overwrite removes those files
/// (throwing naming a file it cannot remove), Continue leaves them (and removes the temporary
/// files of those names that a killed run left). `restarted`, the checkpoint a restart starts
/// from (or empty), is not an earlier run's output: a checkpoint.delta alone in its folder was
/// refused as one, where it starts a new series.
void prepareOutputFolder(const std::filesystem::path& directory, EarlierOutput earlier,
                         const std::filesystem::path& restarted = {});

/// The files in `directory` that a `delta ib --out` run writes (grid.vtu, boundary.vtp, the
/// grid and boundary series and their .pvd, and temporary files a run killed while writing
/// left), sorted. Throws delta::Error naming the folder when it cannot be listed.
std::vector<std::filesystem::path> ibOutputFiles(const std::filesystem::path& directory);

/// What prepareOutputFolder does with `files`, an earlier run's in `directory`: Refuse throws
/// delta::Error "--out 'DIR' holds the output of an earlier run (NAME, …): `hint`", Overwrite
/// removes them (throwing naming a file it cannot remove), Continue leaves them.
void clearEarlierOutput(const std::filesystem::path& directory, EarlierOutput earlier,
                        const std::vector<std::filesystem::path>& files, const std::string& hint);

}  // namespace delta::cli
