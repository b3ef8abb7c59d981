#include "delta/core/memory.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "delta/core/error.h"

namespace delta {
namespace {

/// A cgroup's limit from its file: a number of bytes, or "max" (none).
std::size_t cgroupLimit(const char* path) {
  std::ifstream file(path);
  unsigned long long bytes = 0;
  if (!(file >> bytes) || bytes == 0) return std::numeric_limits<std::size_t>::max();
  return static_cast<std::size_t>(bytes);
}

std::size_t readMemoryLimit() {
  const long pages = ::sysconf(_SC_PHYS_PAGES);
  const long pageSize = ::sysconf(_SC_PAGESIZE);
  std::size_t limit = pages > 0 && pageSize > 0
                          ? static_cast<std::size_t>(pages) * static_cast<std::size_t>(pageSize)
                          : std::numeric_limits<std::size_t>::max();
  for (const char* path :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    const std::size_t cgroup = cgroupLimit(path);
    if (cgroup < limit) limit = cgroup;
  }
  return limit;
}

}  // namespace

std::size_t memoryLimitBytes() noexcept {
  static const std::size_t limit = [] {
    try {
      return readMemoryLimit();
    } catch (...) {
      return std::numeric_limits<std::size_t>::max();
    }
  }();
  return limit;
}

std::string describeBytes(double bytes) {
  char text[48];
  if (!std::isfinite(bytes)) return "an unbounded amount";
  if (bytes < 1e3) {
    std::snprintf(text, sizeof text, "%.0f bytes", bytes);
    return text;
  }
  const char* units[] = {"kB", "MB", "GB", "TB", "PB", "EB", "ZB", "YB"};
  int unit = 0;
  double value = bytes / 1e3;
  while (value >= 1e3 && unit < 7) {
    value /= 1e3;
    ++unit;
  }
  std::snprintf(text, sizeof text, "%.3g %s", value, units[unit]);
  return text;
}

void requireMemory(double bytes, const std::string& what) {
  const std::size_t limit = memoryLimitBytes();
  if (std::isfinite(bytes) && bytes <= static_cast<double>(limit)) return;
  throw Error(what + " would need about " + describeBytes(bytes) + " of memory, more than the " +
              describeBytes(static_cast<double>(limit)) +
              " memory limit (the machine's memory, or its cgroup's limit)");
}

}  // namespace delta
