#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

/// Small allocation-free helpers for the mesh readers (mesh_readers.h): lines, tokens, numbers.
namespace delta::detail {

/// The UTF-8 byte-order mark (U+FEFF) some editors write at the start of a text file: not content.
inline constexpr std::string_view kByteOrderMark = "\xEF\xBB\xBF";

/// `text` without a byte-order mark at its start (a file's first line named "\ufeffOFF" as an
/// unknown keyword, the mark invisible in the message).
inline std::string_view withoutByteOrderMark(std::string_view text) noexcept {
  return text.starts_with(kByteOrderMark) ? text.substr(kByteOrderMark.size()) : text;
}

/// Walks a text line by line, from after a byte-order mark at its start. A line ends at '\n', '\r'
/// or '\f'; runs of line ends are skipped (as assimp's GetNextLine does), so an empty line is never
/// returned.
class LineReader {
 public:
  explicit LineReader(std::string_view text) noexcept : rest_(withoutByteOrderMark(text)) {}

  /// The next non-empty line, without its line end; nullopt at the end of the text.
  std::optional<std::string_view> next() noexcept;

  /// The 1-based number of the line `next()` returned last (counting '\n's, as editors do).
  std::size_t lineNumber() const noexcept { return lineNumber_; }

  /// What has not been returned yet.
  std::string_view rest() const noexcept { return rest_; }

 private:
  std::string_view rest_;
  std::size_t lineNumber_ = 1;
};

/// The first token of `rest` (separated by spaces or tabs), removed from `rest` with the blanks
/// before it; empty when only blanks are left.
std::string_view takeToken(std::string_view& rest) noexcept;

/// `line` without its leading and trailing blanks (spaces, tabs).
std::string_view trimBlanks(std::string_view line) noexcept;

/// Whether `token` starts as assimp's fast_atoreal_move accepts a real number: an optional sign,
/// then a digit, or '.' or ',' before a digit, or "nan" or "inf" (any case).
bool startsLikeNumber(std::string_view token) noexcept;

/// `token` as an unsigned decimal integer (digits only, no sign), or nullopt. Values too large
/// for 64 bits come back as UINT64_MAX, so a caller can say "too large" rather than "garbled".
std::optional<std::uint64_t> parseUnsigned(std::string_view token) noexcept;

/// What parseReal made of a token.
enum class RealStatus {
  ok,          ///< the whole token is a decimal number (or "inf", "nan"), correctly rounded
  notANumber,  ///< empty, garbled, or with characters after the number
  outOfRange,  ///< a decimal beyond the range of double (1e999), or so small it rounds to 0
};

/// A token parsed as a real number.
struct ParsedReal {
  double value = 0.0;
  RealStatus status = RealStatus::notANumber;
};

/// The whole of `token` as a double, correctly rounded from its decimal text (std::from_chars,
/// general format; a leading '+' is allowed). "inf" and "nan" parse as such: callers check
/// finiteness, to say "not finite".
ParsedReal parseReal(std::string_view token) noexcept;

/// Throws delta::Error if `text` holds a NUL byte: assimp's text readers stop there.
void requireText(std::string_view text);

/// `text` cut to at most 40 characters, for quoting a bad line in a message: printable
/// (core/format.h), so that binary garbage is shown as "\xNN" rather than written to the terminal.
std::string excerpt(std::string_view text);

}  // namespace delta::detail
