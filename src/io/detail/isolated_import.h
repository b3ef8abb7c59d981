#pragma once

#include <cstdint>
#include <functional>

#include "mesh_readers.h"

namespace delta::detail {

/// What a child process may use before it is stopped.
struct IsolationLimits {
  /// The address space it may add to what the caller's process maps at the fork (RLIMIT_AS):
  /// an allocation beyond fails in the child. 0: no limit. Not applied in builds with
  /// AddressSanitizer or ThreadSanitizer, which reserve terabytes for their shadow memory.
  std::uint64_t addressSpaceBytes = 0;
  unsigned cpuSeconds = 60;    ///< its processor time (RLIMIT_CPU), then SIGXCPU/SIGKILL
  unsigned wallSeconds = 120;  ///< the time the parent waits for its answer, then SIGKILL
};

/// Runs `import` in a child process (fork) and returns the soup it made, so that a crash, an
/// abort, an escaped exception, exhausted memory or an endless loop in the code it runs (assimp's
/// readers) ends the child, not the caller. The child runs `import` with `limits` set, writes the
/// soup (or the delta::Error it threw) to a pipe and _exit()s; the parent reads at most
/// `limits.addressSpaceBytes` bytes (if set) with the wall-time limit, and waits for the child.
///
/// Throws delta::Error: the message of the error `import` threw; "assimp crashed (signal 11,
/// Segmentation fault) reading it" and the like when the child died of a signal (SIGKILL after
/// the wall time: "did not finish within N s"); when fork or pipe fail; when the child's answer
/// is malformed.
///
/// `import` must be safe to run in the child of a fork from a multithreaded process: it may
/// allocate (glibc's malloc is reset for the child) but must not wait on other threads, locks
/// they may hold, or OpenMP.
///
/// Threading: may be called from several threads at once (each call has its own pipe and child;
/// the pipe's descriptors are close-on-exec).
TriangleSoup runIsolated(const std::function<TriangleSoup()>& import,
                         const IsolationLimits& limits);

}  // namespace delta::detail
