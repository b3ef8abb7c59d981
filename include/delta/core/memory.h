#pragma once

#include <cstddef>
#include <string>

/// @file
/// The memory a request may need before Δ refuses it: every size that grows with a user's number
/// (a primitive's segments, a point count, a grid's levels) is checked against it before anything
/// is allocated, so that an impossible request is an error that says what it would need, not a
/// std::bad_alloc or the kernel's OOM killer.

namespace delta {

/// The memory limit: the machine's physical memory, or the memory limit of the cgroup the
/// process runs in where that is lower (cgroup v2 memory.max, v1 memory.limit_in_bytes). Read
/// once, at the first call.
///
/// Threading: may be called from any thread.
std::size_t memoryLimitBytes() noexcept;

/// `bytes` for a person: "812 bytes", "1.5 MB", "88.4 GB" (powers of 1000).
///
/// Threading: a pure function.
std::string describeBytes(double bytes);

/// Throws delta::Error "WHAT would need about X of memory, more than the N memory limit (the
/// machine's memory, or its cgroup's limit)" when `bytes` (an estimate from the counts,
/// computed in double so that it cannot wrap) exceeds memoryLimitBytes() or is not finite.
///
/// Threading: may be called from any thread.
void requireMemory(double bytes, const std::string& what);

}  // namespace delta
