#pragma once

#include <filesystem>
#include <string>
#include <string_view>

/// @file
/// Files written whole or not at all: every file Δ writes (VTK, CSV, meshes) goes through here.

namespace delta::io {

/// A file that replaces `path` only once it has been written completely: the bytes go to a new
/// temporary file in the same folder (".NAME.delta-XXXXXXXX", created exclusively), and commit()
/// flushes it, fsyncs it, closes it and renames it over `path` (then fsyncs the folder), so a
/// reader sees the previous file or the new one, never a part. Every write, the fsync, the close
/// and the rename are checked.
///
/// - A symlink at `path` is kept: the file it points at (followed through every link) is the one
///   replaced, with the temporary file beside that target.
/// - An existing regular file's permission bits (and, where allowed, its owner) pass to the new
///   file; a new file gets 0666 less the umask, as a plain open would. A file the process may
///   not write (access(2)) is refused, as a plain open would refuse it.
/// - A `path` that exists and is neither a regular file nor a folder (a character device such as
///   /dev/full, a FIFO), or that lies under /proc or /dev/fd or links there (/dev/stdout, whatever
///   is behind it), is written in place, appended to what it holds, each write checked, since it
///   cannot be replaced. Other regular files under /dev (on the /dev/shm tmpfs) are replaced as
///   any other.
///
/// Throws delta::Error "cannot write 'PATH': REASON" (the reason from the system: "No space left
/// on device", "File too large", "Permission denied"...) when the folder is missing or not
/// writable, `path` is a folder, or any write, the fsync, the close or the rename fails. On every
/// failure, and when the object is destroyed without commit(), the temporary file is removed and
/// the previous file at `path` is left as it was. Writing to a file as it is being replaced by
/// another writer is not coordinated: the last rename wins.
///
/// Threading: one object per thread; objects for different paths may be used at once.
class AtomicFile {
 public:
  /// Creates the temporary file (or opens the device or FIFO at `path`).
  explicit AtomicFile(const std::filesystem::path& path);
  /// Removes the temporary file unless commit() has succeeded; never throws.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  /// Appends `bytes` (buffered: a failure may be reported by a later write or by commit()).
  void write(std::string_view bytes);
  /// Writes what is buffered, fsyncs, closes and renames the file into place. Call once; after a
  /// failure the object holds nothing and only its destructor may run.
  void commit();

  /// The path as given.
  const std::filesystem::path& path() const noexcept { return path_; }

 private:
  void writeAll(const char* data, std::size_t size);
  [[noreturn]] void fail(const std::string& reason);
  void discard() noexcept;

  std::filesystem::path path_;       ///< as given, for messages
  std::filesystem::path target_;     ///< `path` with its symlinks followed
  std::filesystem::path temporary_;  ///< empty when writing a device or FIFO in place
  int descriptor_ = -1;
  std::string buffer_;
  bool committed_ = false;
  int tracked_ = -1;  ///< the temporary file's slot for discardTemporaryFiles(), or −1
};

/// Removes the temporary file of every AtomicFile of this process that is being written (made,
/// neither committed nor discarded yet), without closing or unregistering anything: for a
/// program's SIGINT or SIGTERM handler that then ends the process, so that a run stopped while
/// it writes leaves the previous files and no temporary one (the `delta` tool does this).
/// Async-signal-safe (atomic loads and unlink(2) only). Up to kTrackedTemporaryFiles files at
/// once are known to it; those beyond are removed only by their destructors.
///
/// Threading: may be called from a signal handler on any thread while AtomicFiles are made and
/// committed on others.
void discardTemporaryFiles() noexcept;

/// How many temporary files discardTemporaryFiles() knows of at once.
inline constexpr int kTrackedTemporaryFiles = 64;

/// Writes `bytes` to `path` through an AtomicFile: the whole of it replaces the file, or nothing
/// changes and delta::Error names the path and the reason. Threading: as AtomicFile.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace delta::io
