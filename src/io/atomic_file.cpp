#include "delta/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "delta/core/error.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

/// Bytes gathered before a write(2): large enough that a CSV written row by row costs few calls.
constexpr std::size_t kBufferBytes = std::size_t{1} << 20;

/// Links followed before giving up, as the kernel's own limit (ELOOP) does.
constexpr int kMaxLinks = 40;

std::string systemReason(int error) {
  return std::generic_category().message(error);
}

/// `path` with its symlinks followed (a relative link is relative to the link's folder), to the
/// file it names, which need not exist yet.
fs::path followLinks(const fs::path& path) {
  fs::path current = path;
  for (int hops = 0; hops <= kMaxLinks; ++hops) {
    struct stat status {};
    if (::lstat(current.c_str(), &status) != 0 || !S_ISLNK(status.st_mode)) return current;
    std::error_code error;
    const fs::path link = fs::read_symlink(current, error);
    if (error) throw Error("cannot read the link '" + current.string() + "': " + error.message());
    current = link.is_absolute() ? link : current.parent_path() / link;
  }
  throw Error("too many levels of symbolic links");
}

/// Whether `path`, or a link on the way from it to its file, lies under /proc or /dev/fd
/// (/dev/stdout → /proc/self/fd/1 → whatever the process was handed): a stream the process
/// holds, whatever file is behind it, never a file to replace. Other paths under /dev (a file on
/// the /dev/shm tmpfs) are files like any other: a rule on the prefix /dev appended to them.
bool isStream(const fs::path& path) {
  fs::path current = path;
  for (int hops = 0; hops <= kMaxLinks; ++hops) {
    std::error_code error;
    const std::string text = fs::absolute(current, error).lexically_normal().string();
    if (text.starts_with("/proc/") || text.starts_with("/dev/fd/")) return true;
    struct stat status {};
    if (::lstat(current.c_str(), &status) != 0 || !S_ISLNK(status.st_mode)) return false;
    const fs::path link = fs::read_symlink(current, error);
    if (error) return false;
    current = link.is_absolute() ? link : current.parent_path() / link;
  }
  return false;
}

/// 16 hex digits that differ between calls, threads and processes (the name is then created
/// with O_EXCL, which settles any collision).
std::string uniqueSuffix() {
  static std::atomic<std::uint64_t> counter{0};
  std::uint64_t x =
      (static_cast<std::uint64_t>(::getpid()) << 32) ^
      counter.fetch_add(1, std::memory_order_relaxed) * 0x9e3779b97f4a7c15ull ^
      static_cast<std::uint64_t>(std::chrono::steady_clock::now().time_since_epoch().count());
  // splitmix64's finaliser: neighbouring inputs give unrelated names.
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  x ^= x >> 31;
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(x));
  return text;
}

/// The temporary files being written, for discardTemporaryFiles(): a slot is taken (0 → 1), its
/// path written, then published (1 → 2); a signal handler reads only published slots.
struct TrackedPath {
  std::atomic<int> state{0};  ///< 0 free, 1 being filled, 2 published
  char path[PATH_MAX];
};
static_assert(std::atomic<int>::is_always_lock_free, "read from signal handlers");
TrackedPath trackedPaths[kTrackedTemporaryFiles];

/// The slot that now names `path` (made absolute: the handler may run after a chdir), or −1
/// where none is free, the path is too long or it cannot be made absolute.
int track(const fs::path& path) noexcept {
  std::string text;
  try {
    std::error_code error;
    text = fs::absolute(path, error).string();
    if (error) return -1;
  } catch (...) {  // out of memory: the file is then left to its destructor
    return -1;
  }
  if (text.size() >= PATH_MAX) return -1;
  for (int slot = 0; slot < kTrackedTemporaryFiles; ++slot) {
    int expected = 0;
    TrackedPath& tracked = trackedPaths[slot];
    if (!tracked.state.compare_exchange_strong(expected, 1, std::memory_order_acquire)) continue;
    std::memcpy(tracked.path, text.c_str(), text.size() + 1);
    tracked.state.store(2, std::memory_order_release);
    return slot;
  }
  return -1;
}

void untrack(int& slot) noexcept {
  if (slot >= 0) trackedPaths[slot].state.store(0, std::memory_order_release);
  slot = -1;
}

/// fsyncs a folder so that a rename into it survives a crash; where the file system cannot
/// (EINVAL), the rename stands as it is.
void syncFolder(const fs::path& folder) {
  const int descriptor = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (descriptor < 0) return;
  ::fsync(descriptor);
  ::close(descriptor);
}

}  // namespace

AtomicFile::AtomicFile(const fs::path& path) : path_(path) {
  try {
    if (path.empty()) throw Error("the path is empty");
    struct stat existing {};
    const bool exists = ::stat(path.c_str(), &existing) == 0;  // through every link
    if (exists && S_ISDIR(existing.st_mode)) throw Error("it is a folder");
    if (exists && (!S_ISREG(existing.st_mode) || isStream(path))) {
      // A device or FIFO cannot be replaced, nor what /dev/stdout names: write it in place,
      // after what the stream holds.
      descriptor_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
      if (descriptor_ < 0) throw Error(systemReason(errno));
      return;
    }
    target_ = followLinks(path);
    if (target_.filename().empty()) throw Error("the path names a folder");
    // A file its owner made read-only stays so: the rename would replace it regardless.
    if (exists && ::access(target_.c_str(), W_OK) != 0) throw Error(systemReason(errno));
    const fs::path folder = target_.has_parent_path() ? target_.parent_path() : fs::path(".");
    // The name is kept short enough for NAME_MAX (255) with the prefix and suffix.
    std::string stem(1, '.');  // (appended piece by piece: GCC 12 warns on "." + string)
    stem.append(target_.filename().string(), 0, 200);
    stem.append(".delta-");
    for (int attempt = 0; descriptor_ < 0; ++attempt) {
      temporary_ = folder / (stem + uniqueSuffix());
      // Listed before it exists: a signal between the open and the listing would leave it.
      tracked_ = track(temporary_);
      descriptor_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (descriptor_ < 0) {
        const int error = errno;
        untrack(tracked_);  // the name is not this object's (EEXIST: another file's)
        if (error != EEXIST || attempt == 100) {
          temporary_.clear();
          throw Error("cannot make a temporary file in '" + folder.string() +
                      "': " + systemReason(error));
        }
      }
    }
    if (exists) {
      // The replacement keeps the file's owner (where allowed) and permissions.
      if (existing.st_uid != ::geteuid() || existing.st_gid != ::getegid())
        if (::fchown(descriptor_, existing.st_uid, existing.st_gid) != 0) {
          // Not the owner's to give: the new file stays the writer's, as a new file would.
        }
      if (::fchmod(descriptor_, existing.st_mode & 07777) != 0) throw Error(systemReason(errno));
    }
  } catch (const Error& error) {
    discard();
    throw Error("cannot write '" + path.string() + "': " + error.what());
  }
  buffer_.reserve(kBufferBytes);
}

AtomicFile::~AtomicFile() {
  discard();
}

void AtomicFile::discard() noexcept {
  if (descriptor_ >= 0) ::close(descriptor_);
  descriptor_ = -1;
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  untrack(tracked_);  // after the unlink: a signal between them unlinks it again, harmlessly
  temporary_.clear();
  buffer_.clear();
}

void AtomicFile::fail(const std::string& reason) {
  discard();
  throw Error("cannot write '" + path_.string() + "': " + reason);
}

void AtomicFile::writeAll(const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t written = ::write(descriptor_, data, size);
    if (written < 0 && errno == EINTR) continue;
    if (written < 0) fail(systemReason(errno));
    if (written == 0) fail(systemReason(ENOSPC));  // no progress: nothing more fits
    data += written;
    size -= static_cast<std::size_t>(written);
  }
}

void AtomicFile::write(std::string_view bytes) {
  if (descriptor_ < 0) fail(committed_ ? "written to after commit()" : "an earlier write failed");
  if (buffer_.size() + bytes.size() > kBufferBytes) {
    writeAll(buffer_.data(), buffer_.size());
    buffer_.clear();
    if (bytes.size() >= kBufferBytes) {
      writeAll(bytes.data(), bytes.size());
      return;
    }
  }
  buffer_.append(bytes);
}

void AtomicFile::commit() {
  if (descriptor_ < 0) fail(committed_ ? "committed twice" : "an earlier write failed");
  writeAll(buffer_.data(), buffer_.size());
  buffer_.clear();
  if (!temporary_.empty() && ::fsync(descriptor_) != 0) fail(systemReason(errno));
  const int closed = ::close(descriptor_);
  descriptor_ = -1;
  if (closed != 0 && errno != EINTR) fail(systemReason(errno));
  if (!temporary_.empty()) {
    if (::rename(temporary_.c_str(), target_.c_str()) != 0) fail(systemReason(errno));
    untrack(tracked_);  // a signal before this finds nothing left to unlink
    temporary_.clear();
    syncFolder(target_.has_parent_path() ? target_.parent_path() : fs::path("."));
  }
  committed_ = true;
}

void discardTemporaryFiles() noexcept {
  for (TrackedPath& tracked : trackedPaths)
    if (tracked.state.load(std::memory_order_acquire) == 2) ::unlink(tracked.path);
}

void writeFileAtomically(const fs::path& path, std::string_view bytes) {
  AtomicFile file(path);
  file.write(bytes);
  file.commit();
}

}  // namespace delta::io
