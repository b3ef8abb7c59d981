#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

/// Reading input files without trusting them: only regular files, never more than they hold.
namespace delta::io {

/// An open regular file, closed on destruction.
///
/// Opening checks the file type on the opened descriptor (no race between check and open), and
/// opens without blocking, so that a FIFO, a device (/dev/zero), a socket or a directory is
/// refused at once instead of blocking or streaming forever.
///
/// Threading: one object per thread; different objects may be used concurrently.
class RegularFile {
 public:
  /// Throws delta::Error (without the path: callers add it) for a missing file ("no such
  /// file"), a directory, anything else that is not a regular file, or a file that cannot be
  /// opened.
  explicit RegularFile(const std::filesystem::path& path);
  ~RegularFile();
  RegularFile(const RegularFile&) = delete;
  RegularFile& operator=(const RegularFile&) = delete;

  /// The size the file had when it was opened.
  std::uintmax_t size() const noexcept { return size_; }

  /// Up to `count` bytes from `offset`, fewer only where the file ends sooner; never more than
  /// size() - offset, so a file that grows while it is read cannot make this read more. Throws
  /// delta::Error when reading fails.
  std::string read(std::uintmax_t offset, std::uintmax_t count) const;

  /// The whole file as it was when opened: read(0, size()).
  std::string readAll() const { return read(0, size_); }

 private:
  int descriptor_ = -1;
  std::uintmax_t size_ = 0;
};

/// The whole regular file at `path`, refused if it holds more than `limit` bytes (the error names
/// both sizes and `what` the file is, e.g. "a DEM config"). Throws delta::Error as RegularFile
/// does, without the path.
std::string readSmallRegularFile(const std::filesystem::path& path, std::uintmax_t limit,
                                 const std::string& what);

}  // namespace delta::io
