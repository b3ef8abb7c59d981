#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

/// The fuzzer's bytes as a file with a given extension, rewritten for every input: the public
/// readers take paths. The file lives in /dev/shm where there is one (memory, no disk traffic),
/// named after the process so that parallel fuzzing jobs do not share it.
class FuzzFile {
 public:
  explicit FuzzFile(const std::string& extension) {
    const std::filesystem::path folder = std::filesystem::is_directory("/dev/shm")
                                             ? "/dev/shm"
                                             : std::filesystem::temp_directory_path();
    path_ = folder / ("delta_fuzz_" + std::to_string(getpid()) + extension);
  }
  ~FuzzFile() { std::remove(path_.c_str()); }
  FuzzFile(const FuzzFile&) = delete;
  FuzzFile& operator=(const FuzzFile&) = delete;

  /// Replaces the file's content with `bytes`; aborts if it cannot (a broken harness, not a
  /// finding).
  const std::filesystem::path& write(const std::uint8_t* bytes, std::size_t size) {
    std::FILE* file = std::fopen(path_.c_str(), "wb");
    if (file == nullptr || std::fwrite(bytes, 1, size, file) != size || std::fclose(file) != 0) {
      std::perror(path_.c_str());
      std::abort();
    }
    return path_;
  }

 private:
  std::filesystem::path path_;
};
