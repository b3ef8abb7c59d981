#include "run_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <regex>
#include <sstream>
#include <system_error>
#include <vector>

#include "delta/core/error.h"

namespace delta::cli {
namespace {

std::string reasonOf(int error) {
  return std::generic_category().message(error);
}

/// What a lock file says: "PID HOST COMMAND…", or empty.
std::string readAll(int descriptor) {
  std::string text;
  char buffer[256];
  if (::lseek(descriptor, 0, SEEK_SET) != 0) return text;
  for (ssize_t got; (got = ::read(descriptor, buffer, sizeof buffer)) > 0 && text.size() < 4096;)
    text.append(buffer, static_cast<std::size_t>(got));
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r'))
    text.pop_back();
  return text;
}

std::string hostName() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown-host";
  return name;
}

/// "delta dem, pid N on HOST" from "N HOST delta dem".
std::string holderOf(const std::string& text) {
  std::istringstream fields(text);
  std::string pid, host, command;
  fields >> pid >> host;
  std::getline(fields >> std::ws, command);
  if (pid.empty()) return "another run (its lock file is still being written)";
  return (command.empty() ? "a run" : command) + ", pid " + pid +
         (host.empty() ? "" : " on " + host);
}

}  // namespace

RunLock::RunLock(const std::filesystem::path& directory, const std::string& command)
    : path_(directory / kRunLockName), pathText_(path_.string()) {
  const std::string where = "--out '" + directory.string() + "'";
  // A run that ends unlinks the file it locked; one that opened that file before the unlink
  // would lock a file no longer in the folder, so the lock counts only while the path still
  // names the file locked. A few tries cover the races.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int descriptor = ::open(pathText_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (descriptor < 0)
      throw Error("cannot make the lock file '" + pathText_ + "': " + reasonOf(errno));
    if (::flock(descriptor, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      const std::string holder = readAll(descriptor);
      ::close(descriptor);
      if (error == EWOULDBLOCK)
        throw Error(where + " is in use by " + holderOf(holder) +
                    " (one run at a time writes into a folder)");
      throw Error("cannot lock '" + pathText_ + "': " + reasonOf(error));
    }
    struct stat held {
    }, named{};
    if (::fstat(descriptor, &held) != 0 || ::stat(pathText_.c_str(), &named) != 0 ||
        held.st_ino != named.st_ino || held.st_dev != named.st_dev) {
      ::close(descriptor);  // unlinked by its last holder meanwhile: try the new one
      continue;
    }
    const std::string previous = readAll(descriptor);
    if (!previous.empty())
      note_ = "took over the lock file of " + holderOf(previous) + ", which has ended";
    const std::string line = std::to_string(::getpid()) + " " + hostName() + " " + command + "\n";
    if (::ftruncate(descriptor, 0) != 0 ||
        ::pwrite(descriptor, line.data(), line.size(), 0) != static_cast<ssize_t>(line.size())) {
      const int error = errno;
      ::close(descriptor);
      throw Error("cannot write the lock file '" + pathText_ + "': " + reasonOf(error));
    }
    descriptor_ = descriptor;
    return;
  }
  throw Error(where + ": cannot lock '" + pathText_ + "': it keeps being replaced");
}

RunLock::~RunLock() {
  release();
}

void RunLock::release() noexcept {
  const int descriptor = descriptor_.exchange(-1);
  if (descriptor < 0) return;
  ::unlink(pathText_.c_str());  // while still locked: no other run holds this file
  ::close(descriptor);
}

namespace {

/// The names DemOutput and DemCheckpoints write (dem_output.h, dem_checkpoint.h).
constexpr const char* kDemNames =
    R"((log\.csv|obstacles\.vtp|shape_[0-9]+\.vtp|checkpoint\.delta|\.delta\.run|)"
    R"((particles_state|particles|contacts|obstacles)(\.pvd|_[0-9]{6,}(_[0-9]+)?\.(vtp|pvtp))))";

/// The files of `directory` (not folders) whose names match `names`, sorted.
std::vector<std::filesystem::path> filesNamed(const std::filesystem::path& directory,
                                              const std::regex& names) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  std::filesystem::directory_iterator entries(directory, error);
  if (error)
    throw Error("--out '" + directory.string() + "': cannot list the folder: " + error.message());
  for (const std::filesystem::directory_entry& entry : entries) {
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, names) && !entry.is_directory(error)) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace

std::vector<std::filesystem::path> demOutputFiles(const std::filesystem::path& directory) {
  // And AtomicFile's temporaries (".NAME.delta-…") of any name.
  static const std::regex kNames(std::string(kDemNames) + R"(|\..+\.delta-[A-Za-z0-9]+)");
  return filesNamed(directory, kNames);
}

void prepareOutputFolder(const std::filesystem::path& directory, EarlierOutput earlier,
                         const std::filesystem::path& restarted) {
  if (earlier == EarlierOutput::Continue) {
    // The temporary files of the run's own names that a run killed while writing left
    // (AtomicFile's ".NAME.delta-" and 16 hex digits): no run of this folder writes them now
    // (the lock is held), and they would stay for ever.
    static const std::regex kStale("\\.(" + std::string(kDemNames) + ")\\.delta-[0-9a-f]{16}");
    for (const std::filesystem::path& file : filesNamed(directory, kStale)) {
      std::error_code error;
      std::filesystem::remove(file, error);  // one left is no harm
    }
    return;
  }
  std::vector<std::filesystem::path> files = demOutputFiles(directory);
  if (!restarted.empty())
    std::erase_if(files, [&](const std::filesystem::path& file) {
      std::error_code error;
      return std::filesystem::equivalent(file, restarted, error);
    });
  clearEarlierOutput(directory, earlier, files, "--overwrite replaces it, --restart continues it");
}

std::vector<std::filesystem::path> ibOutputFiles(const std::filesystem::path& directory) {
  // The names `delta ib` writes, and AtomicFile's temporaries (".NAME.delta-…") of any name.
  static const std::regex kNames(
      R"(((grid|boundary)(\.pvd|_[0-9]{6,}\.(vtu|vtp))|grid\.vtu|boundary\.vtp|)"
      R"(\..+\.delta-[A-Za-z0-9]+))");
  return filesNamed(directory, kNames);
}

void clearEarlierOutput(const std::filesystem::path& directory, EarlierOutput earlier,
                        const std::vector<std::filesystem::path>& files, const std::string& hint) {
  if (files.empty() || earlier == EarlierOutput::Continue) return;
  if (earlier == EarlierOutput::Refuse) {
    // Named by what a user sees first: the hidden files (the run marker, temporaries) last.
    std::vector<std::filesystem::path> shown = files;
    std::stable_partition(shown.begin(), shown.end(), [](const std::filesystem::path& file) {
      return !file.filename().string().starts_with('.');
    });
    std::string names;
    for (std::size_t k = 0; k < std::min<std::size_t>(shown.size(), 3); ++k)
      names += (k ? ", " : "") + shown[k].filename().string();
    if (files.size() > 3) names += ", … " + std::to_string(files.size()) + " files";
    throw Error("--out '" + directory.string() + "' holds the output of an earlier run (" + names +
                "): " + hint);
  }
  for (const std::filesystem::path& file : files) {
    std::error_code error;
    std::filesystem::remove(file, error);
    if (error)
      throw Error("--overwrite: cannot remove '" + file.string() + "': " + error.message());
  }
}

}  // namespace delta::cli
