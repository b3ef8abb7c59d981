// STL, binary (80-byte comment, 32-bit triangle count, 50 bytes a facet) and ascii.
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"

#include "mesh_readers.h"
#include "reader_support.h"
#include "soup_builder.h"
#include "text_scan.h"

namespace delta::detail {
namespace {

constexpr std::size_t kHeaderBytes = 84;    // 80-byte comment + 32-bit triangle count
constexpr std::size_t kTriangleBytes = 50;  // normal, 3 vertices (12 floats) + 16-bit attribute

std::uint32_t littleEndian32(std::string_view bytes, std::size_t at) noexcept {
  std::uint32_t value = 0;
  for (std::size_t i = 0; i < 4; ++i)
    value |= std::uint32_t{static_cast<unsigned char>(bytes[at + i])} << (8 * i);
  return value;
}

TriangleSoup readBinary(std::string_view bytes) {
  const std::uint32_t count = littleEndian32(bytes, 80);
  SoupBuilder soup;
  std::vector<Vec3>& vertices = soup.vertices();
  vertices.reserve(std::size_t{3} * count);  // the file's size is 84 + 50 * count
  std::uint32_t corners[3];
  for (std::uint32_t t = 0; t < count; ++t) {
    const std::size_t facet = kHeaderBytes + std::size_t{t} * kTriangleBytes;
    for (std::uint32_t corner = 0; corner < 3; ++corner) {
      Vec3 position;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const std::size_t at = facet + 12 + 12 * corner + 4 * axis;
        // float32 to double is exact: the file's number, nothing rounded.
        position[axis] = std::bit_cast<float>(littleEndian32(bytes, at));
      }
      if (!isFinite(position))
        throw Error("triangle " + std::to_string(t) + " (byte " + std::to_string(facet) +
                    ") has a corner that is not finite: " + toString(position));
      corners[corner] = static_cast<std::uint32_t>(vertices.size());
      vertices.push_back(position);
    }
    soup.addFace(corners);
  }
  return soup.finish(false);
}

bool isBlankByte(char c) noexcept {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

/// Whitespace-separated tokens with their line numbers.
class Tokens {
 public:
  explicit Tokens(std::string_view text) : rest_(text) {}

  /// The next token; empty at the end of the text.
  std::string_view next() noexcept {
    std::size_t start = 0;
    for (; start < rest_.size() && isBlankByte(rest_[start]); ++start)
      if (rest_[start] == '\n') ++line_;
    std::size_t end = start;
    while (end < rest_.size() && !isBlankByte(rest_[end]))
      ++end;
    const std::string_view token = rest_.substr(start, end - start);
    rest_.remove_prefix(end);
    return token;
  }

  /// Skips the rest of the current line (a solid's name).
  void skipLine() noexcept {
    const std::size_t end = rest_.find('\n');
    rest_.remove_prefix(end == rest_.npos ? rest_.size() : end);
  }

  std::size_t line() const noexcept { return line_; }

 private:
  std::string_view rest_;
  std::size_t line_ = 1;
};

bool isKeyword(std::string_view token, std::string_view keyword) noexcept {
  if (token.size() != keyword.size()) return false;
  for (std::size_t i = 0; i < token.size(); ++i)
    if ((token[i] | 0x20) != keyword[i]) return false;  // ASCII lower case
  return true;
}

class AsciiStl {
 public:
  explicit AsciiStl(std::string_view text) : tokens_(text) {}

  TriangleSoup read() {
    std::string_view token = tokens_.next();
    if (!isKeyword(token, "solid")) failAtLine(tokens_.line(), "an ascii STL starts with 'solid'");
    while (isKeyword(token, "solid")) {
      tokens_.skipLine();  // the solid's name
      soup_.beginMesh();
      for (token = tokens_.next(); isKeyword(token, "facet"); token = tokens_.next())
        facet();
      if (token.empty())
        failAtLine(tokens_.line(), "the ascii STL ends without 'endsolid': the file is cut short");
      if (!isKeyword(token, "endsolid"))
        failAtLine(tokens_.line(),
                   "expected 'facet' or 'endsolid', found '" + excerpt(token) + "'");
      tokens_.skipLine();  // the solid's name again
      token = tokens_.next();
    }
    if (!token.empty())
      failAtLine(tokens_.line(),
                 "expected 'solid' or the end of the file after 'endsolid', found '" +
                     excerpt(token) + "'");
    return soup_.finish(false);
  }

 private:
  void expect(std::string_view keyword) {
    const std::string_view token = tokens_.next();
    if (token.empty())
      failAtLine(tokens_.line(),
                 "the ascii STL ends inside a facet, without 'endsolid': the "
                 "file is cut short");
    if (!isKeyword(token, keyword))
      failAtLine(tokens_.line(),
                 "expected '" + std::string(keyword) + "', found '" + excerpt(token) + "'");
  }

  void facet() {
    std::string_view token = tokens_.next();
    if (isKeyword(token, "normal")) {
      for (int i = 0; i < 3; ++i)  // the normal is of no use to Δ, but must be there
        if (!startsLikeNumber(tokens_.next()))
          failAtLine(tokens_.line(), "a facet normal needs three numbers");
      token = tokens_.next();
    }
    if (!isKeyword(token, "outer"))
      failAtLine(tokens_.line(), "expected 'outer loop', found '" + excerpt(token) + "'");
    expect("loop");
    corners_.clear();
    for (token = tokens_.next(); isKeyword(token, "vertex"); token = tokens_.next()) {
      Vec3 position;
      for (std::size_t axis = 0; axis < 3; ++axis)
        position[axis] = parseCoordinate(tokens_.next(), tokens_.line());
      corners_.push_back(static_cast<std::uint32_t>(soup_.vertices().size()));
      soup_.vertices().push_back(position);
    }
    if (!isKeyword(token, "endloop"))
      failAtLine(tokens_.line(),
                 token.empty() ? std::string("the ascii STL ends inside a facet, "
                                             "without 'endsolid': the file is cut "
                                             "short")
                               : "expected 'vertex' or 'endloop', found '" + excerpt(token) + "'");
    if (corners_.size() < 3)
      failAtLine(tokens_.line(), "a facet has " + std::to_string(corners_.size()) +
                                     " vertices; it needs at least 3");
    expect("endfacet");
    soup_.addFace(corners_);
  }

  Tokens tokens_;
  SoupBuilder soup_;
  std::vector<std::uint32_t> corners_;
};

bool startsWithSolid(std::string_view bytes) noexcept {
  const std::size_t start = bytes.find_first_not_of(" \t\r\n\f");
  return start != bytes.npos && isKeyword(bytes.substr(start, 5), "solid");
}

}  // namespace

bool isBinaryStlOfAnnouncedSize(std::string_view head, std::uintmax_t size) noexcept {
  return head.size() >= kHeaderBytes &&
         size == kHeaderBytes + std::uintmax_t{littleEndian32(head, 80)} * kTriangleBytes;
}

void requireStlStart(std::string_view head, std::uintmax_t size) {
  if (isBinaryStlOfAnnouncedSize(head, size)) return;
  if (startsWithSolid(head) && head.find('\0') == head.npos) return;
  if (size < kHeaderBytes)
    throw Error("the file has " + std::to_string(size) +
                " bytes: too short for a binary STL, whose header alone takes 84");
  const std::uint32_t triangles = littleEndian32(head, 80);
  throw Error("the binary STL has " + std::to_string(size) + " bytes, but its header " +
              "announces " + std::to_string(triangles) + " triangles, which take 84 + 50 * " +
              std::to_string(triangles) + " = " +
              std::to_string(kHeaderBytes + std::uint64_t{triangles} * kTriangleBytes) +
              " bytes: the file is truncated or has bytes appended");
}

TriangleSoup readStl(std::string_view bytes) {
  requireStlStart(bytes, bytes.size());
  if (isBinaryStlOfAnnouncedSize(bytes, bytes.size())) return readBinary(bytes);
  return AsciiStl(bytes).read();
}

}  // namespace delta::detail
