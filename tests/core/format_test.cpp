#include "delta/core/format.h"

#include <gtest/gtest.h>

#include <string>

namespace delta {
namespace {

using namespace std::string_literals;

TEST(Printable, KeepsTextAndValidUtf8) {
  EXPECT_EQ(printable("scenario = settle"), "scenario = settle");
  EXPECT_EQ(printable("r\xC3\xA9sum\xC3\xA9 \xE2\x88\x86 \xF0\x9F\x98\x80"),
            "r\xC3\xA9sum\xC3\xA9 \xE2\x88\x86 \xF0\x9F\x98\x80");
  EXPECT_EQ(printable(""), "");
}

TEST(Printable, WritesEveryByteThatIsNotPrintableTextInHex) {
  // A NUL cut a message short where it was read as a C string; garbage reached the terminal raw.
  EXPECT_EQ(printable("two-\0particles"s), "two-\\x00particles");
  EXPECT_EQ(printable("\x1B[2J\x07\x7F\t\r\n"), "\\x1B[2J\\x07\\x7F\\x09\\x0D\\x0A");
  // The C1 controls, stray continuation bytes, overlong forms, surrogates, beyond U+10FFFF,
  // sequences cut short.
  EXPECT_EQ(printable("\xC2\x85"), "\\xC2\\x85");
  EXPECT_EQ(printable("\x80\xBF"), "\\x80\\xBF");
  EXPECT_EQ(printable("\xC0\xAF\xE0\x80\xAF"), "\\xC0\\xAF\\xE0\\x80\\xAF");
  EXPECT_EQ(printable("\xED\xA0\x80"), "\\xED\\xA0\\x80");
  EXPECT_EQ(printable("\xF4\x90\x80\x80"), "\\xF4\\x90\\x80\\x80");
  EXPECT_EQ(printable("a\xE2\x88"), "a\\xE2\\x88");
  EXPECT_EQ(printable("\xFF\xFE"), "\\xFF\\xFE");
  for (int byte = 0; byte < 256; ++byte) {
    const std::string out = printable(std::string(1, static_cast<char>(byte)));
    for (char c : out)
      EXPECT_TRUE(c >= 0x20 && c < 0x7F) << "byte " << byte << " gave " << out;
  }
}

TEST(Printable, CutsAtTheLimitInCharactersNeverInsideOne) {
  EXPECT_EQ(printable("abcdef", 4), "abcd...");
  EXPECT_EQ(printable("abcd", 4), "abcd");
  EXPECT_EQ(printable("\xC3\xA9\xC3\xA9\xC3\xA9", 2), "\xC3\xA9\xC3\xA9...");
  EXPECT_EQ(printable("\x01\x02\x03", 2), "\\x01\\x02...");
  EXPECT_EQ(printable(std::string(1000, 'x')).size(), 83u);
}

}  // namespace
}  // namespace delta
