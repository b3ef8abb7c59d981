#include "isolated_import.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <new>
#include <string>
#include <system_error>

#include "delta/core/error.h"

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define DELTA_SANITIZED_BUILD 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define DELTA_SANITIZED_BUILD 1
#endif
#endif

namespace delta::detail {
namespace {

constexpr char kSoup = 'S';
constexpr char kError = 'E';

/// The counts that precede the arrays of a soup in the child's answer.
struct SoupHeader {
  std::uint64_t positions = 0;
  std::uint64_t triangles = 0;
  std::uint64_t meshes = 0;
  std::uint64_t sourceVertices = 0;
  std::uint64_t pointsSkipped = 0;
  std::uint64_t linesSkipped = 0;
};

/// Writes all of `bytes` (child side); false when the pipe failed.
bool writeAll(int descriptor, const void* bytes, std::size_t size) noexcept {
  const char* at = static_cast<const char*>(bytes);
  while (size > 0) {
    const ssize_t written = ::write(descriptor, at, size);
    if (written < 0 && errno == EINTR) continue;
    if (written <= 0) return false;
    at += written;
    size -= static_cast<std::size_t>(written);
  }
  return true;
}

void writeError(int descriptor, const char* message) noexcept {
  writeAll(descriptor, &kError, 1);
  writeAll(descriptor, message, std::strlen(message));
}

/// The address space the calling process maps now (/proc/self/statm), in bytes; 0 if unknown.
std::uint64_t mappedBytes() noexcept {
  const int descriptor = ::open("/proc/self/statm", O_RDONLY | O_CLOEXEC);
  if (descriptor < 0) return 0;
  char text[64] = {};
  const ssize_t got = ::read(descriptor, text, sizeof text - 1);
  ::close(descriptor);
  if (got <= 0) return 0;
  std::uint64_t pages = 0;
  for (const char* c = text; *c >= '0' && *c <= '9'; ++c)
    pages = 10 * pages + static_cast<std::uint64_t>(*c - '0');
  return pages * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

/// A crash of the child ends it by its signal, whatever handlers the caller installed: a Python
/// interpreter's faulthandler would print the parent's traceback, a sanitizer's handler would
/// turn the signal into an exit status.
void restoreDefaultCrashHandling() noexcept {
  sigset_t crashes;
  sigemptyset(&crashes);
  for (const int signal : {SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT, SIGTRAP, SIGSYS}) {
    struct sigaction action {};
    action.sa_handler = SIG_DFL;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
    sigaddset(&crashes, signal);
  }
  ::pthread_sigmask(SIG_UNBLOCK, &crashes, nullptr);
}

[[noreturn]] void runChild(int descriptor, const std::function<TriangleSoup()>& import,
                           const IsolationLimits& limits, std::uint64_t mappedAtFork) noexcept {
  restoreDefaultCrashHandling();
#ifndef DELTA_SANITIZED_BUILD
  if (limits.addressSpaceBytes != 0 && mappedAtFork != 0) {
    const rlim_t bytes = mappedAtFork + limits.addressSpaceBytes;
    const rlimit memory{bytes, bytes};
    ::setrlimit(RLIMIT_AS, &memory);
  }
#else
  (void)mappedAtFork;
#endif
  const rlimit cpu{limits.cpuSeconds, limits.cpuSeconds + 1};
  ::setrlimit(RLIMIT_CPU, &cpu);
  try {
    const TriangleSoup soup = import();
    const SoupHeader header{soup.positions.size(),         soup.triangles.size(),
                            soup.statistics.meshes,        soup.statistics.sourceVertices,
                            soup.statistics.pointsSkipped, soup.statistics.linesSkipped};
    const bool written =
        writeAll(descriptor, &kSoup, 1) && writeAll(descriptor, &header, sizeof header) &&
        writeAll(descriptor, soup.positions.data(), soup.positions.size() * sizeof(Vec3)) &&
        writeAll(descriptor, soup.triangles.data(),
                 soup.triangles.size() * sizeof(TriangleIndices));
    ::_exit(written ? 0 : 3);
  } catch (const std::bad_alloc&) {
    writeError(descriptor, "assimp ran out of memory reading it");
  } catch (const std::exception& error) {
    writeError(descriptor, error.what());
  } catch (...) {
    writeError(descriptor, "assimp failed with an unknown exception");
  }
  ::_exit(0);
}

/// The child's whole answer, read until it closes the pipe; throws when it exceeds `limit` bytes
/// (when set) or takes longer than `wallSeconds`.
std::string readAnswer(int descriptor, std::uint64_t limit, unsigned wallSeconds, bool& timedOut) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(wallSeconds);
  std::string answer;
  char buffer[1 << 16];
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timedOut = true;
      return answer;
    }
    pollfd readable{descriptor, POLLIN, 0};
    const int ready = ::poll(&readable, 1, static_cast<int>(left.count()));
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0)
      throw Error("waiting for assimp failed: " + std::generic_category().message(errno));
    if (ready == 0) continue;  // the deadline check above ends it
    const ssize_t got = ::read(descriptor, buffer, sizeof buffer);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0)
      throw Error("reading assimp's answer failed: " + std::generic_category().message(errno));
    if (got == 0) return answer;
    answer.append(buffer, static_cast<std::size_t>(got));
    if (limit != 0 && answer.size() > limit + sizeof(SoupHeader) + 1)
      throw Error("assimp's answer exceeds the memory its process may use");
  }
}

/// The status of the child, waited for.
int reap(pid_t child) {
  int status = 0;
  while (::waitpid(child, &status, 0) < 0)
    if (errno != EINTR) return 0;
  return status;
}

TriangleSoup parseAnswer(const std::string& answer) {
  if (answer.empty()) throw Error("assimp ended without an answer");
  if (answer[0] == kError) throw Error(answer.substr(1));
  if (answer[0] != kSoup || answer.size() < 1 + sizeof(SoupHeader))
    throw Error("assimp's answer is malformed");
  SoupHeader header;
  std::memcpy(&header, answer.data() + 1, sizeof header);
  const std::size_t body = answer.size() - 1 - sizeof header;
  if (header.positions > body / sizeof(Vec3) ||
      header.triangles > (body - header.positions * sizeof(Vec3)) / sizeof(TriangleIndices) ||
      body != header.positions * sizeof(Vec3) + header.triangles * sizeof(TriangleIndices))
    throw Error("assimp's answer is malformed: its counts do not match its size");
  TriangleSoup soup;
  soup.positions.resize(static_cast<std::size_t>(header.positions));
  soup.triangles.resize(static_cast<std::size_t>(header.triangles));
  const char* at = answer.data() + 1 + sizeof header;
  std::memcpy(soup.positions.data(), at, soup.positions.size() * sizeof(Vec3));
  std::memcpy(soup.triangles.data(), at + soup.positions.size() * sizeof(Vec3),
              soup.triangles.size() * sizeof(TriangleIndices));
  for (const TriangleIndices& triangle : soup.triangles)
    for (const std::uint32_t corner : triangle)
      if (corner >= soup.positions.size()) throw Error("assimp's answer has a bad index");
  soup.statistics.meshes = static_cast<std::size_t>(header.meshes);
  soup.statistics.sourceVertices = static_cast<std::size_t>(header.sourceVertices);
  soup.statistics.pointsSkipped = static_cast<std::size_t>(header.pointsSkipped);
  soup.statistics.linesSkipped = static_cast<std::size_t>(header.linesSkipped);
  soup.statistics.precision = io::CoordinatePrecision::single;
  return soup;
}

}  // namespace

TriangleSoup runIsolated(const std::function<TriangleSoup()>& import,
                         const IsolationLimits& limits) {
  const std::uint64_t mappedAtFork = mappedBytes();
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0)
    throw Error("cannot make a pipe for assimp: " + std::generic_category().message(errno));
  const pid_t child = ::fork();
  if (child < 0) {
    const int error = errno;
    ::close(ends[0]);
    ::close(ends[1]);
    throw Error("cannot start a process for assimp: " + std::generic_category().message(error));
  }
  if (child == 0) {
    ::close(ends[0]);
    runChild(ends[1], import, limits, mappedAtFork);
  }
  ::close(ends[1]);
  bool timedOut = false;
  std::string answer;
  try {
    const std::uint64_t limit =
        limits.addressSpaceBytes == 0 ? 0 : mappedAtFork + limits.addressSpaceBytes;
    answer = readAnswer(ends[0], limit, limits.wallSeconds, timedOut);
  } catch (...) {
    ::close(ends[0]);
    ::kill(child, SIGKILL);
    reap(child);
    throw;
  }
  ::close(ends[0]);
  if (timedOut) ::kill(child, SIGKILL);
  const int status = reap(child);
  if (timedOut)
    throw Error("assimp did not finish reading it within " + std::to_string(limits.wallSeconds) +
                " s; stopped");
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    if (signal == SIGXCPU || signal == SIGKILL)
      throw Error("assimp used more than " + std::to_string(limits.cpuSeconds) +
                  " s of processor time reading it; stopped (signal " + std::to_string(signal) +
                  ")");
    const char* description = ::sigdescr_np(signal);
    throw Error("assimp crashed (signal " + std::to_string(signal) +
                (description != nullptr ? std::string(", ") + description : std::string()) +
                ") reading it");
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
    throw Error("assimp's process exited with status " + std::to_string(WEXITSTATUS(status)) +
                " reading it");
  return parseAnswer(answer);
}

}  // namespace delta::detail
