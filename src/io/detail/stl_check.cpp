#include <cstdint>
#include <string>
#include <string_view>

#include "delta/core/error.h"
#include "delta/io/detail/format_checks.h"
#include "delta/io/detail/text_scan.h"

namespace delta::io::detail {
namespace {

constexpr std::size_t kHeaderBytes = 84;    // 80-byte comment + 32-bit triangle count
constexpr std::size_t kTriangleBytes = 50;  // normal, 3 vertices (12 floats) + 16-bit attribute

std::uint32_t announcedTriangles(std::string_view bytes) {
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < 4; ++i)  // little-endian
    count |= std::uint32_t{static_cast<unsigned char>(bytes[80 + i])} << (8 * i);
  return count;
}

/// As assimp decides: text that starts with "solid"; a binary file with a header that starts
/// with "solid" (common) still has NUL bytes in its triangle count or data.
bool isAsciiStl(std::string_view bytes) {
  const std::size_t start = bytes.find_first_not_of(" \t\r\n\f");
  return start != bytes.npos && bytes.substr(start).starts_with("solid") &&
         bytes.find('\0') == bytes.npos;
}

void checkAsciiEnd(std::string_view text) {
  const std::size_t lastChar = text.find_last_not_of(" \t\r\n\f");  // exists: text has "solid"
  const std::size_t lineEnd = text.find_last_of("\r\n\f", lastChar);
  const std::size_t lineStart = lineEnd == text.npos ? 0 : lineEnd + 1;
  const std::string_view last = trimBlanks(text.substr(lineStart, lastChar + 1 - lineStart));
  if (!last.starts_with("endsolid"))
    throw Error("the ascii STL does not end with 'endsolid' (its last line is '" + excerpt(last) +
                "'): the file is cut short");
}

}  // namespace

bool isBinaryStlOfAnnouncedSize(std::string_view head, std::uintmax_t size) {
  return head.size() >= kHeaderBytes &&
         size == kHeaderBytes + std::uintmax_t{announcedTriangles(head)} * kTriangleBytes;
}

void checkStl(std::string_view bytes) {
  if (isBinaryStlOfAnnouncedSize(bytes, bytes.size())) return;
  if (isAsciiStl(bytes)) return checkAsciiEnd(bytes);
  if (bytes.size() < kHeaderBytes)
    throw Error("the file has " + std::to_string(bytes.size()) +
                " bytes: too short for a binary STL, whose header alone takes 84");
  const std::uint32_t triangles = announcedTriangles(bytes);
  throw Error("the binary STL has " + std::to_string(bytes.size()) + " bytes, but its header " +
              "announces " + std::to_string(triangles) + " triangles, which take 84 + 50 * " +
              std::to_string(triangles) + " = " +
              std::to_string(kHeaderBytes + std::uint64_t{triangles} * kTriangleBytes) +
              " bytes: the file is truncated or has bytes appended");
}

}  // namespace delta::io::detail
