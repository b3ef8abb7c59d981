// The OFF check mirrors assimp 5.2's OFFImporter::InternReadFile: a token-wise header, then
// exactly one vertex or face per line, each read into a 4096-byte line buffer.
#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "delta/core/error.h"
#include "delta/io/detail/format_checks.h"
#include "delta/io/detail/text_scan.h"

namespace delta::io::detail {
namespace {

constexpr std::size_t kAssimpLineBuffer = 4096;
constexpr std::uint64_t kAssimpMaxFaceVertices = 9;
constexpr std::uint64_t kAssimpMaxCount = std::numeric_limits<std::uint32_t>::max();

[[noreturn]] void fail(std::size_t line, const std::string& what) {
  throw Error("line " + std::to_string(line) + ": " + what);
}

/// The header's fields. A vertex line needs `coordinates` numbers.
struct OffHeader {
  std::uint64_t vertices = 0;
  std::uint64_t faces = 0;
  std::size_t coordinates = 3;
};

/// Header tokens, then whole lines, as assimp reads them.
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

 private:
  LineReader lines_;
  std::string_view current_;
};

std::uint64_t parseCount(std::string_view token, std::size_t line, const std::string& what) {
  if (token.empty())
    fail(line, "the line of counts must hold the vertex, face and edge counts; the " + what +
                   " count is missing");
  const std::optional<std::uint64_t> count = parseUnsigned(token);
  if (!count) fail(line, "the " + what + " count '" + excerpt(token) + "' is not a number");
  if (*count > kAssimpMaxCount)
    fail(line, "the " + what + " count " + std::string(token) +
                   " does not fit in 32 bits (assimp would wrap it)");
  return *count;
}

/// Reads the rest of `[ST][C][N][4][n]OFF` (the dimension after `n`); returns the number of
/// coordinates on a vertex line.
std::size_t readKeyword(OffReader& reader, std::string_view keyword) {
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (prefix.find_first_not_of("STCN4n") != prefix.npos)
    fail(reader.lineNumber(), "unknown OFF keyword '" + excerpt(keyword) + "'");
  std::size_t coordinates = 3;
  if (prefix.find('n') != prefix.npos) {
    const std::optional<std::uint64_t> dimension = parseUnsigned(reader.nextToken());
    if (!dimension || *dimension < 1 || *dimension > 3)
      fail(reader.lineNumber(), "the dimension after nOFF must be 1, 2 or 3");
    coordinates = static_cast<std::size_t>(*dimension);
  }
  if (prefix.find('4') != prefix.npos) ++coordinates;  // homogeneous w
  return coordinates;
}

OffHeader readHeader(OffReader& reader) {
  OffHeader header;
  std::string_view token = reader.nextToken();
  if (token.ends_with("OFF")) {
    header.coordinates = readKeyword(reader, token);
    token = reader.nextToken();
  }
  if (token.empty()) fail(reader.lineNumber(), "the file ends before the vertex and face counts");
  const std::size_t line = reader.lineNumber();
  header.vertices = parseCount(token, line, "vertex");
  header.faces = parseCount(reader.nextTokenOnLine(), line, "face");
  parseCount(reader.nextTokenOnLine(), line, "edge");
  if (header.vertices == 0) fail(line, "the header announces no vertices");
  if (header.faces == 0) fail(line, "the header announces no faces");
  return header;
}

std::string elementName(const char* kind, std::uint64_t index) {
  std::string name = kind;
  name += ' ';
  name += std::to_string(index);
  return name;
}

std::string_view nextElementLine(OffReader& reader, const OffHeader& header, const char* kind,
                                 std::uint64_t index) {
  const std::optional<std::string_view> line = reader.nextLine();
  if (!line)
    fail(reader.lineNumber(), "the file ends at " + elementName(kind, index) +
                                  ", but the header announces " + std::to_string(header.vertices) +
                                  " vertices and " + std::to_string(header.faces) + " faces");
  if (line->size() >= kAssimpLineBuffer)
    fail(reader.lineNumber(), "the line has " + std::to_string(line->size()) +
                                  " characters; assimp's OFF reader takes at most " +
                                  std::to_string(kAssimpLineBuffer - 1));
  return *line;
}

void checkVertex(OffReader& reader, const OffHeader& header, std::uint64_t index) {
  const std::string_view line = nextElementLine(reader, header, "vertex", index);
  std::string_view rest = line;
  for (std::size_t i = 0; i < header.coordinates; ++i)
    if (!startsLikeNumber(takeToken(rest)))
      fail(reader.lineNumber(), elementName("vertex", index) + " needs " +
                                    std::to_string(header.coordinates) + " numbers, found '" +
                                    excerpt(trimBlanks(line)) + "'");
}

void checkFace(OffReader& reader, const OffHeader& header, std::uint64_t index) {
  const std::string_view line = nextElementLine(reader, header, "face", index);
  const std::size_t lineNumber = reader.lineNumber();
  const auto failFace = [&](const std::string& what) {
    fail(lineNumber, elementName("face", index) + what);
  };
  std::string_view rest = line;
  const std::string_view sizeToken = takeToken(rest);
  const std::optional<std::uint64_t> size = parseUnsigned(sizeToken);
  if (!size)
    fail(lineNumber,
         "expected " + elementName("face", index) + ", found '" + excerpt(trimBlanks(line)) + "'");
  if (*size == 0) failFace(" has no vertices");
  if (*size > kAssimpMaxFaceVertices)
    failFace(" has " + std::string(sizeToken) +
             " vertices; assimp's OFF reader drops faces with more than " +
             std::to_string(kAssimpMaxFaceVertices));
  for (std::uint64_t corner = 0; corner < *size; ++corner) {
    const std::string_view token = takeToken(rest);
    const std::optional<std::uint64_t> vertex = parseUnsigned(token);
    if (!vertex)
      failFace(" needs " + std::to_string(*size) + " vertex indices, found '" +
               excerpt(trimBlanks(line)) + "'");
    if (*vertex >= header.vertices)
      failFace(" refers to vertex " + std::string(token) + ", but there are only " +
               std::to_string(header.vertices) + " vertices");
  }
}

/// `text` with every comment ('#' to the end of its line) cut, and the blanks before it; line
/// ends stay, so line numbers do.
std::string withoutComments(std::string_view text) {
  std::string stripped(text.size(), '\0');
  char* out = stripped.data();
  char* contentEnd = out;  // just after the last non-blank of the line
  bool inComment = false;
  for (const char c : text) {
    if (c == '\n' || c == '\r' || c == '\f') {
      out = contentEnd;  // drops the blanks before the comment or the line end
      inComment = false;
    } else if (inComment || c == '#') {
      inComment = true;
      continue;
    }
    *out++ = c;
    if (c != ' ' && c != '\t') contentEnd = out;
  }
  stripped.resize(static_cast<std::size_t>(contentEnd - stripped.data()));
  return stripped;
}

/// The keyword for prefix `[ST][C][N][4][n]` without the colour, normal and texture flags.
std::string geometryKeyword(std::string_view prefix) {
  std::string keyword;
  for (const char flag : prefix)
    if (flag == '4' || flag == 'n') keyword.push_back(flag);
  return keyword + "OFF";
}

}  // namespace

std::string offForAssimp(std::string_view text) {
  std::string prepared = withoutComments(text);
  const std::size_t start = prepared.find_first_not_of(" \t\r\n\f");
  if (start == prepared.npos) return prepared;
  const std::size_t end = std::min(prepared.find_first_of(" \t\r\n\f", start), prepared.size());
  const std::string_view keyword = std::string_view(prepared).substr(start, end - start);
  const std::string_view prefix = keyword.substr(0, keyword.size() - 3);
  if (keyword.ends_with("OFF") && prefix.find_first_not_of("STCN4n") == prefix.npos)
    prepared.replace(start, keyword.size(), geometryKeyword(prefix));
  return prepared;
}

void checkOff(std::string_view text) {
  requireText(text);
  OffReader reader(text);
  const OffHeader header = readHeader(reader);
  for (std::uint64_t v = 0; v < header.vertices; ++v)
    checkVertex(reader, header, v);
  for (std::uint64_t f = 0; f < header.faces; ++f)
    checkFace(reader, header, f);
  if (const std::optional<std::string_view> line = reader.nextLine())
    fail(reader.lineNumber(), "more lines than the " + std::to_string(header.faces) +
                                  " faces the header announces: '" + excerpt(*line) + "'");
}

}  // namespace delta::io::detail
