// Reading back what io::writeVtp and io::writeVtu emit, for the tests of the writers and of what
// is converted to VTK: raw or zlib-compressed appended data (io/vtk.h), decompressed here with
// zlib itself so that the tests do not trust the writer's own encoding.
#pragma once

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <type_traits>
#include <vector>

namespace delta::test {

/// A file's bytes.
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// The VTK type name of T, as the writers declare it.
template <typename T>
constexpr const char* vtkTypeOf() {
  if constexpr (std::is_same_v<T, double>) return "Float64";
  if constexpr (std::is_same_v<T, std::int64_t>) return "Int64";
  if constexpr (std::is_same_v<T, std::int32_t>) return "Int32";
  if constexpr (std::is_same_v<T, std::uint32_t>) return "UInt32";
  if constexpr (std::is_same_v<T, std::uint8_t>) return "UInt8";
}

inline std::uint64_t uint64At(const std::string& file, std::size_t at) {
  std::uint64_t value = 0;
  EXPECT_LE(at + sizeof value, file.size()) << "a header past the end of the file";
  if (at + sizeof value <= file.size()) std::memcpy(&value, file.data() + at, sizeof value);
  return value;
}

/// The bytes of the appended array that starts at `at`: for a compressed file the blocks of
/// vtkZLibDataCompressor (UInt64 header: blocks, block size, last partial block size, each
/// block's compressed size; then the zlib streams), else a UInt64 byte count and the bytes.
/// A malformed array is a test failure.
inline std::string appendedBytes(const std::string& file, std::size_t at, bool compressed) {
  if (!compressed) {
    const std::uint64_t size = uint64At(file, at);
    EXPECT_LE(at + 8 + size, file.size());
    return at + 8 + size <= file.size() ? file.substr(at + 8, size) : std::string();
  }
  const std::uint64_t blocks = uint64At(file, at), blockSize = uint64At(file, at + 8);
  const std::uint64_t lastSize = uint64At(file, at + 16);
  std::size_t next = at + 8 * (3 + blocks);
  std::string bytes;
  for (std::uint64_t b = 0; b < blocks; ++b) {
    const std::uint64_t compressedSize = uint64At(file, at + 8 * (3 + b));
    uLongf size = b + 1 == blocks && lastSize != 0 ? lastSize : blockSize;
    std::string block(size, '\0');
    EXPECT_LE(next + compressedSize, file.size());
    if (next + compressedSize > file.size()) return {};
    const int status = uncompress(reinterpret_cast<Bytef*>(block.data()), &size,
                                  reinterpret_cast<const Bytef*>(file.data() + next),
                                  static_cast<uLong>(compressedSize));
    EXPECT_EQ(status, Z_OK) << "block " << b;
    EXPECT_EQ(size, b + 1 == blocks && lastSize != 0 ? lastSize : blockSize) << "block " << b;
    bytes += block;
    next += compressedSize;
  }
  return bytes;
}

/// The values of the DataArray named `name` (the first of that name) in the text of a VTK XML
/// file: a minimal reader of what the writers emit (offset attribute, raw or compressed
/// little-endian values). The array must be declared as T's VTK type; a missing array or
/// another type is a test failure and reads as empty.
template <typename T>
std::vector<T> readVtkArray(const std::string& file, const std::string& name) {
  const std::regex element("<DataArray type=\"([A-Za-z0-9]+)\" Name=\"" + name +
                           "\"[^>]* offset=\"([0-9]+)\"");
  std::smatch match;
  EXPECT_TRUE(std::regex_search(file, match, element)) << name;
  if (match.empty()) return {};
  EXPECT_EQ(match[1].str(), vtkTypeOf<T>()) << name;
  if (match[1].str() != vtkTypeOf<T>()) return {};
  const std::string marker = "<AppendedData encoding=\"raw\">\n_";
  const std::size_t start = file.find(marker) + marker.size();
  const bool compressed =
      file.substr(0, start).find("compressor=\"vtkZLibDataCompressor\"") != std::string::npos;
  const std::string bytes = appendedBytes(file, start + std::stoull(match[2]), compressed);
  EXPECT_EQ(bytes.size() % sizeof(T), 0u) << name;
  std::vector<T> values(bytes.size() / sizeof(T));
  if (!values.empty()) std::memcpy(values.data(), bytes.data(), values.size() * sizeof(T));
  return values;
}

}  // namespace delta::test
