// OFF as Princeton's and CGAL's files write it (the Geomview OFF format): a token-wise header,
// then one vertex or face a line; comments anywhere.
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "delta/core/error.h"

#include "mesh_readers.h"
#include "reader_support.h"
#include "soup_builder.h"
#include "text_scan.h"

namespace delta::detail {
namespace {

constexpr std::uint64_t kMaxCount = std::numeric_limits<std::uint32_t>::max();

/// The header's fields. A vertex line starts with `coordinates` numbers, then `w` if `homogeneous`.
struct OffHeader {
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;
  std::size_t coordinates = 3;
  bool homogeneous = false;
};

/// Lines without their comments ('#' to the end of the line); blank ones skipped.
class OffLines {
 public:
  explicit OffLines(std::string_view text) : lines_(text) {}

  std::optional<std::string_view> next() noexcept {
    for (std::optional<std::string_view> line = lines_.next(); line; line = lines_.next()) {
      const std::string_view content = trimBlanks(line->substr(0, line->find('#')));
      if (!content.empty()) return content;
    }
    return std::nullopt;
  }

  std::size_t lineNumber() const noexcept { return lines_.lineNumber(); }
  std::size_t bytesLeft() const noexcept { return lines_.rest().size(); }

 private:
  LineReader lines_;
};

/// Header tokens, then whole lines.
class OffReader {
 public:
  explicit OffReader(std::string_view text) : lines_(text) {}

  /// The next header token, on this line or the next; empty at the end of the file.
  std::string_view nextToken() {
    for (std::string_view token = takeToken(current_);; token = takeToken(current_)) {
      if (!token.empty()) return token;
      const std::optional<std::string_view> line = lines_.next();
      if (!line) return {};
      current_ = *line;
    }
  }

  /// The next header token on the current line; empty at its end.
  std::string_view nextTokenOnLine() { return takeToken(current_); }

  /// The next body line: what is left of the header's last line, then one line at a time.
  std::optional<std::string_view> nextLine() {
    if (!trimBlanks(current_).empty()) return std::exchange(current_, {});
    return lines_.next();
  }

  std::size_t lineNumber() const noexcept { return lines_.lineNumber(); }
  std::size_t bytesLeft() const noexcept { return lines_.bytesLeft() + current_.size(); }

 private:
  OffLines lines_;
  std::string_view current_;
};

std::uint64_t parseCount(std::string_view token, std::size_t line, const std::string& what) {
  if (token.empty())
    failAtLine(line, "the line of counts must hold the vertex, face and edge counts; the " + what +
                         " count is missing");
  const std::optional<std::uint64_t> count = parseUnsigned(token);
  if (!count) failAtLine(line, "the " + what + " count '" + excerpt(token) + "' is not a number");
  if (*count > kMaxCount)
    failAtLine(line, "the " + what + " count " + std::string(token) +
                         " does not fit in 32 bits (Δ's vertex indices)");
  return *count;
}

/// Reads the rest of `[ST][C][N][4][n]OFF` (the dimension after `n`).
void readKeyword(OffReader& reader, std::string_view keyword, OffHeader& header) {
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find_first_not_of("STCN4n") != prefix.npos)
    failAtLine(reader.lineNumber(), "unknown OFF keyword '" + excerpt(keyword) + "'");
  if (prefix.find('n') != prefix.npos) {
    const std::optional<std::uint64_t> dimension = parseUnsigned(reader.nextToken());
    if (!dimension || *dimension < 1 || *dimension > 3)
      failAtLine(reader.lineNumber(), "the dimension after nOFF must be 1, 2 or 3");
    header.coordinates = static_cast<std::size_t>(*dimension);
  }
  header.homogeneous = prefix.find('4') != prefix.npos;
}

OffHeader readHeader(OffReader& reader) {
  OffHeader header;
  std::string_view token = reader.nextToken();
  if (token.ends_with("OFF")) {
    readKeyword(reader, token, header);
    token = reader.nextToken();
  }
  if (token.empty())
    failAtLine(reader.lineNumber(), "the file ends before the vertex and face counts");
  const std::size_t line = reader.lineNumber();
  header.vertices = parseCount(token, line, "vertex");
  header.faces = parseCount(reader.nextTokenOnLine(), line, "face");
  parseCount(reader.nextTokenOnLine(), line, "edge");
  if (header.vertices == 0) failAtLine(line, "the header announces no vertices");
  if (header.faces == 0) failAtLine(line, "the header announces no faces");
  // Each vertex and face takes a line of at least two bytes with its line end: a lying count
  // is refused before anything is allocated for it.
  const std::uint64_t atMost = reader.bytesLeft() / 2 + 1;
  if (header.vertices > atMost || header.faces > atMost - std::min(atMost, header.vertices))
    failAtLine(line, "the header announces " + std::to_string(header.vertices) + " vertices and " +
                         std::to_string(header.faces) + " faces, but the " +
                         std::to_string(reader.bytesLeft()) + " bytes after it hold at most " +
                         std::to_string(atMost) + " lines");
  return header;
}

std::string elementName(const char* kind, std::uint64_t index) {
  return std::string(kind) + " " + std::to_string(index);
}

std::string_view nextElementLine(OffReader& reader, const OffHeader& header, const char* kind,
                                 std::uint64_t index) {
  const std::optional<std::string_view> line = reader.nextLine();
  if (!line)
    failAtLine(reader.lineNumber(), "the file ends at " + elementName(kind, index) +
                                        ", but the header announces " +
                                        std::to_string(header.vertices) + " vertices and " +
                                        std::to_string(header.faces) + " faces");
  return *line;
}

Vec3 readVertex(OffReader& reader, const OffHeader& header, std::uint64_t index) {
  const std::string_view line = nextElementLine(reader, header, "vertex", index);
  const std::size_t lineNumber = reader.lineNumber();
  const std::size_t needed = header.coordinates + (header.homogeneous ? 1 : 0);
  std::string_view rest = line;
  Vec3 position;
  double w = 1.0;
  for (std::size_t i = 0; i < needed; ++i) {
    const std::string_view token = takeToken(rest);
    if (token.empty())
      failAtLine(lineNumber, elementName("vertex", index) + " needs " + std::to_string(needed) +
                                 " numbers, found '" + excerpt(line) + "'");
    const double value = parseCoordinate(token, lineNumber);
    if (i < header.coordinates)
      position[i] = value;
    else
      w = value;
  }
  if (w != 1.0) {
    if (w == 0.0)
      failAtLine(lineNumber, elementName("vertex", index) + " has w = 0: a point at infinity");
    position = position / w;
    if (!isFinite(position))
      failAtLine(lineNumber, elementName("vertex", index) + " divided by its w is not finite");
  }
  return position;
}

void readFace(OffReader& reader, const OffHeader& header, std::uint64_t index,
              std::vector<std::uint32_t>& corners, SoupBuilder& soup) {
  const std::string_view line = nextElementLine(reader, header, "face", index);
  const std::size_t lineNumber = reader.lineNumber();
  const auto failFace = [&](const std::string& what) {
    failAtLine(lineNumber, elementName("face", index) + what);
  };
  std::string_view rest = line;
  const std::optional<std::uint64_t> size = parseUnsigned(takeToken(rest));
  if (!size)
    failAtLine(lineNumber,
               "expected " + elementName("face", index) + ", found '" + excerpt(line) + "'");
  if (*size == 0) failFace(" has no vertices");
  if (*size > rest.size() / 2 + 1)
    failFace(" announces " + std::to_string(*size) + " vertices, but its line is shorter");
  corners.clear();
  for (std::uint64_t corner = 0; corner < *size; ++corner) {
    const std::string_view token = takeToken(rest);
    const std::optional<std::uint64_t> vertex = parseUnsigned(token);
    if (!vertex)
      failFace(" needs " + std::to_string(*size) + " vertex indices, found '" + excerpt(line) +
               "'");
    if (*vertex >= header.vertices)
      failFace(" refers to vertex " + std::string(token) + ", but there are only " +
               std::to_string(header.vertices) + " vertices");
    corners.push_back(static_cast<std::uint32_t>(*vertex));
  }
  soup.addFace(corners);  // what follows the indices is the face's colour
}

}  // namespace

TriangleSoup readOff(std::string_view text) {
  requireText(text);
  OffReader reader(text);
  const OffHeader header = readHeader(reader);
  SoupBuilder soup;
  std::vector<Vec3>& vertices = soup.vertices();
  vertices.reserve(static_cast<std::size_t>(header.vertices));
  for (std::uint64_t v = 0; v < header.vertices; ++v)
    vertices.push_back(readVertex(reader, header, v));
  std::vector<std::uint32_t> corners;
  for (std::uint64_t f = 0; f < header.faces; ++f)
    readFace(reader, header, f, corners, soup);
  if (const std::optional<std::string_view> line = reader.nextLine())
    failAtLine(reader.lineNumber(), "more lines than the " + std::to_string(header.faces) +
                                        " faces the header announces: '" + excerpt(*line) + "'");
  return soup.finish(false);
}

}  // namespace delta::detail
