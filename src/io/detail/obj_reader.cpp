// Wavefront OBJ geometry: vertices and the faces, lines and points on them.
#include <charconv>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"

#include "mesh_readers.h"
#include "reader_support.h"
#include "soup_builder.h"
#include "text_scan.h"

namespace delta::detail {
namespace {

/// A statement continued with a backslash at the ends of its lines, joined (rare, so it may
/// allocate).
std::string joinContinuedLines(std::string_view first, LineReader& lines) {
  std::string statement(trimBlanks(first));
  while (!statement.empty() && statement.back() == '\\') {
    statement.back() = ' ';
    const std::optional<std::string_view> next = lines.next();
    if (!next) break;
    statement += trimBlanks(*next);
  }
  return statement;
}

class ObjReader {
 public:
  void statement(std::string_view text, std::size_t line) {
    std::string_view rest = text;
    const std::string_view keyword = takeToken(rest);
    if (keyword == "v") return vertex(rest, text, line);
    if (keyword == "f" || keyword == "l" || keyword == "p") return element(keyword, rest, line);
    if (keyword == "o" || keyword == "g") soup_.beginMesh();
    // Anything else (vt, vn, usemtl, mtllib, s, comments) carries no geometry Δ reads.
  }

  TriangleSoup finish() { return soup_.finish(true); }

 private:
  void vertex(std::string_view values, std::string_view text, std::size_t line) {
    Vec3 position;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const std::string_view token = takeToken(values);
      if (token.empty())
        failAtLine(line, "a vertex needs three numbers, found '" + excerpt(trimBlanks(text)) + "'");
      position[axis] = parseCoordinate(token, line);
    }
    if (soup_.vertices().size() == std::numeric_limits<std::uint32_t>::max())
      failAtLine(line, "more than 2^32 - 1 vertices");
    soup_.vertices().push_back(position);  // a w or a colour after them is of no use to Δ
  }

  /// The vertex a reference `v`, `v/vt`, `v/vt/vn` or `v//vn` names: 1-based, or negative,
  /// counted back from the last vertex defined so far.
  std::uint32_t vertexIndex(std::string_view reference, std::size_t line) const {
    const std::string_view number = reference.substr(0, reference.find('/'));
    std::int64_t index = 0;
    const char* end = number.data() + number.size();
    const auto [stop, status] = std::from_chars(number.data(), end, index);
    if (number.empty() || status != std::errc() || stop != end)
      failAtLine(line, "'" + excerpt(reference) + "' is not a vertex reference");
    const auto defined = static_cast<std::int64_t>(soup_.vertices().size());
    if (index == 0) failAtLine(line, "vertex index 0: OBJ counts vertices from 1");
    const std::int64_t zeroBased = index > 0 ? index - 1 : defined + index;
    if (zeroBased < 0 || zeroBased >= defined)
      failAtLine(line, "vertex index " + std::string(number) + " names no vertex: " +
                           std::to_string(defined) + " are defined before this line");
    return static_cast<std::uint32_t>(zeroBased);
  }

  void element(std::string_view keyword, std::string_view rest, std::size_t line) {
    corners_.clear();
    for (std::string_view token = takeToken(rest); !token.empty(); token = takeToken(rest))
      corners_.push_back(vertexIndex(token, line));
    if (corners_.empty())
      failAtLine(line, "'" + std::string(keyword) + "' statement without vertices");
    if (keyword == "p") return soup_.addPoints(corners_.size());
    if (keyword == "l") return soup_.addLines(corners_.size() > 1 ? corners_.size() - 1 : 1);
    soup_.addFace(corners_);
  }

  SoupBuilder soup_;
  std::vector<std::uint32_t> corners_;
};

}  // namespace

TriangleSoup readObj(std::string_view text) {
  requireText(text);
  ObjReader reader;
  LineReader lines(text);
  for (std::optional<std::string_view> line = lines.next(); line; line = lines.next()) {
    const std::size_t lineNumber = lines.lineNumber();
    const std::string_view content = line->substr(0, line->find('#'));
    if (trimBlanks(content).ends_with('\\'))
      reader.statement(joinContinuedLines(content, lines), lineNumber);
    else
      reader.statement(content, lineNumber);
  }
  return reader.finish();
}

}  // namespace delta::detail
