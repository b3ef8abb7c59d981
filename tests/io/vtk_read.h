// Reading back what io::writeVtp and io::writeVtu emit, for the tests of the writers and of what
// is converted to VTK.
#pragma once

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

namespace delta::test {

/// A file's bytes.
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// The appended block of the DataArray named `name` in the text of a VTK XML file (a minimal
/// reader of what the writers emit: offset attribute, UInt64 byte count, raw little-endian
/// values). A missing array is a test failure and reads as empty.
template <typename T>
std::vector<T> readVtkArray(const std::string& file, const std::string& name) {
  const std::regex element("<DataArray[^>]* Name=\"" + name + "\"[^>]* offset=\"([0-9]+)\"");
  std::smatch match;
  EXPECT_TRUE(std::regex_search(file, match, element)) << name;
  if (match.empty()) return {};
  const std::string marker = "<AppendedData encoding=\"raw\">\n_";
  const std::size_t start = file.find(marker) + marker.size();
  const std::size_t at = start + std::stoull(match[1]);
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, file.data() + at, sizeof bytes);
  std::vector<T> values(bytes / sizeof(T));
  if (bytes > 0) std::memcpy(values.data(), file.data() + at + sizeof bytes, bytes);
  return values;
}

}  // namespace delta::test
