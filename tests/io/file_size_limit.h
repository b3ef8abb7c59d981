// A full disk, simulated for a test: RLIMIT_FSIZE makes every write past a size fail with EFBIG
// ("File too large") as ENOSPC would, without needing a small file system.
#pragma once

#include <sys/resource.h>

#include <csignal>

namespace delta::test {

/// Lowers this process's file size limit to `bytes` (SIGXFSZ ignored, so that a write past it
/// fails with EFBIG instead of ending the process) until it goes out of scope.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    ::getrlimit(RLIMIT_FSIZE, &saved_);
    previousHandler_ = std::signal(SIGXFSZ, SIG_IGN);
    rlimit lowered = saved_;
    lowered.rlim_cur = bytes;
    ::setrlimit(RLIMIT_FSIZE, &lowered);
  }
  ~FileSizeLimit() {
    ::setrlimit(RLIMIT_FSIZE, &saved_);
    std::signal(SIGXFSZ, previousHandler_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit saved_{};
  void (*previousHandler_)(int) = SIG_DFL;
};

}  // namespace delta::test
