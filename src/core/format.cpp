#include "delta/core/format.h"

#include <cstdint>
#include <sstream>

namespace delta {

std::string toString(const Vec3& v) {
  std::ostringstream text;
  text.precision(17);
  text << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return text.str();
}

std::string toString(double value) {
  std::ostringstream text;
  text.precision(17);
  text << value;
  return text.str();
}

namespace {

/// The length of the valid UTF-8 sequence of a printable character beyond ASCII at the start of
/// `text` (2 to 4 bytes), or 0: overlong forms, surrogates, code points beyond U+10FFFF and the
/// C1 controls (U+0080 to U+009F) are not.
std::size_t printableSequence(std::string_view text) noexcept {
  const auto byte = [&](std::size_t i) { return static_cast<std::uint8_t>(text[i]); };
  const std::uint8_t lead = byte(0);
  std::size_t length = 0;
  std::uint32_t point = 0;
  if (lead >= 0xC2 && lead <= 0xDF) {
    length = 2;
    point = lead & 0x1Fu;
  } else if (lead >= 0xE0 && lead <= 0xEF) {
    length = 3;
    point = lead & 0x0Fu;
  } else if (lead >= 0xF0 && lead <= 0xF4) {
    length = 4;
    point = lead & 0x07u;
  } else {
    return 0;
  }
  if (text.size() < length) return 0;
  for (std::size_t i = 1; i < length; ++i) {
    if ((byte(i) & 0xC0u) != 0x80u) return 0;
    point = point << 6 | (byte(i) & 0x3Fu);
  }
  constexpr std::uint32_t kSmallest[] = {0, 0, 0x80, 0x800, 0x10000};
  if (point < kSmallest[length] || point > 0x10FFFF || (point >= 0xD800 && point <= 0xDFFF))
    return 0;
  return point <= 0x9F ? 0 : length;
}

}  // namespace

std::string printable(std::string_view text, std::size_t limit) {
  constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  std::size_t characters = 0;
  std::size_t i = 0;
  while (i < text.size() && characters < limit) {
    const auto c = static_cast<std::uint8_t>(text[i]);
    if (c >= 0x20 && c < 0x7F) {
      out += static_cast<char>(c);
      ++i;
    } else if (const std::size_t length = c >= 0x80 ? printableSequence(text.substr(i)) : 0;
               length > 0) {
      out.append(text.substr(i, length));
      i += length;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 0xFu];
      ++i;
    }
    ++characters;
  }
  if (i < text.size()) out += "...";
  return out;
}

}  // namespace delta
