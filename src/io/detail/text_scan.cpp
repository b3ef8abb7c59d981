#include "text_scan.h"

#include <charconv>
#include <limits>
#include <system_error>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta::detail {
namespace {

constexpr bool isLineEnd(char c) noexcept {
  return c == '\n' || c == '\r' || c == '\f';
}
constexpr bool isBlank(char c) noexcept {
  return c == ' ' || c == '\t';
}
constexpr bool isDigit(char c) noexcept {
  return c >= '0' && c <= '9';
}

bool startsWithWord(std::string_view text, std::string_view word) noexcept {
  if (text.size() < word.size()) return false;
  for (std::size_t i = 0; i < word.size(); ++i)
    if ((text[i] | 0x20) != word[i]) return false;  // ASCII lower case
  return true;
}

}  // namespace

std::optional<std::string_view> LineReader::next() noexcept {
  std::size_t start = 0;
  for (; start < rest_.size() && isLineEnd(rest_[start]); ++start) {
    const bool crBeforeLf =
        rest_[start] == '\r' && start + 1 < rest_.size() && rest_[start + 1] == '\n';
    if (!crBeforeLf) ++lineNumber_;
  }
  rest_.remove_prefix(start);
  if (rest_.empty()) return std::nullopt;
  std::size_t end = 0;
  while (end < rest_.size() && !isLineEnd(rest_[end]))
    ++end;
  const std::string_view line = rest_.substr(0, end);
  rest_.remove_prefix(end);
  return line;
}

std::string_view takeToken(std::string_view& rest) noexcept {
  std::size_t start = 0;
  while (start < rest.size() && isBlank(rest[start]))
    ++start;
  std::size_t end = start;
  while (end < rest.size() && !isBlank(rest[end]))
    ++end;
  const std::string_view token = rest.substr(start, end - start);
  rest.remove_prefix(end);
  return token;
}

std::string_view trimBlanks(std::string_view line) noexcept {
  while (!line.empty() && isBlank(line.front()))
    line.remove_prefix(1);
  while (!line.empty() && isBlank(line.back()))
    line.remove_suffix(1);
  return line;
}

bool startsLikeNumber(std::string_view token) noexcept {
  if (!token.empty() && (token[0] == '-' || token[0] == '+')) token.remove_prefix(1);
  if (token.empty()) return false;
  if (isDigit(token[0])) return true;
  if ((token[0] == '.' || token[0] == ',') && token.size() > 1 && isDigit(token[1])) return true;
  return startsWithWord(token, "nan") || startsWithWord(token, "inf");
}

std::optional<std::uint64_t> parseUnsigned(std::string_view token) noexcept {
  if (token.empty()) return std::nullopt;
  for (char c : token)
    if (!isDigit(c)) return std::nullopt;
  std::uint64_t value = 0;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  if (result.ec == std::errc::result_out_of_range) return std::numeric_limits<std::uint64_t>::max();
  return value;
}

ParsedReal parseReal(std::string_view token) noexcept {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  const char* end = token.data() + token.size();
  ParsedReal parsed;
  const auto [stop, status] =
      std::from_chars(token.data(), end, parsed.value, std::chars_format::general);
  if (token.empty() || status == std::errc::invalid_argument || stop != end) return {};
  parsed.status =
      status == std::errc::result_out_of_range ? RealStatus::outOfRange : RealStatus::ok;
  return parsed;
}

void requireText(std::string_view text) {
  const std::size_t at = text.find('\0');
  if (at != std::string_view::npos)
    throw Error("byte " + std::to_string(at) + " is a NUL character: this is not a text file");
}

std::string excerpt(std::string_view text) {
  return printable(text, 40);
}

}  // namespace delta::detail
