#include <optional>
#include <string>
#include <string_view>

#include "delta/core/error.h"
#include "delta/io/detail/format_checks.h"
#include "delta/io/detail/text_scan.h"

namespace delta::io::detail {
namespace {

[[noreturn]] void fail(std::size_t line, const std::string& what) {
  throw Error("line " + std::to_string(line) + ": " + what);
}

void checkVertex(std::string_view values, std::size_t line) {
  std::string_view rest = values;
  for (int i = 0; i < 3; ++i)
    if (!startsLikeNumber(takeToken(rest)))
      fail(line, "a vertex needs three numbers, found 'v " + excerpt(trimBlanks(values)) + "'");
}

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

void checkStatement(std::string_view statement, std::size_t line) {
  std::string_view rest = statement;
  const std::string_view keyword = takeToken(rest);
  if (keyword == "v") checkVertex(rest, line);
  const bool element = keyword == "f" || keyword == "l" || keyword == "p";
  if (element && trimBlanks(rest).empty())
    fail(line, "'" + std::string(keyword) + "' statement without vertices");
}

}  // namespace

void checkObj(std::string_view text) {
  requireText(text);
  LineReader lines(text);
  for (std::optional<std::string_view> line = lines.next(); line; line = lines.next()) {
    const std::size_t lineNumber = lines.lineNumber();
    if (trimBlanks(*line).ends_with('\\'))
      checkStatement(joinContinuedLines(*line, lines), lineNumber);
    else
      checkStatement(*line, lineNumber);
  }
}

}  // namespace delta::io::detail
