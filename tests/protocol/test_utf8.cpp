// The UTF-8 check every text reader uses (curvlab/harness/utf8.hpp): the
// first byte that breaks UTF-8, its line and column, and the message.
#include "curvlab/harness/utf8.hpp"

#include <gtest/gtest.h>

namespace {

using curvlab::harness::find_invalid_utf8;

TEST(Utf8, WellFormedTextOfEveryLengthPasses) {
  EXPECT_FALSE(find_invalid_utf8(""));
  EXPECT_FALSE(find_invalid_utf8("plain ASCII\nnote\r\n"));
  // é, €, 𝄞 (2, 3 and 4 bytes), U+FEFF (a BOM), U+10FFFF, U+D7FF, U+E000.
  EXPECT_FALSE(find_invalid_utf8("caf\xC3\xA9 \xE2\x82\xAC \xF0\x9D\x84\x9E \xEF\xBB\xBF \xF4\x8F\xBF\xBF \xED\x9F\xBF "
                                 "\xEE\x80\x80"));
}

TEST(Utf8, TheFirstBadByteIsFoundWithItsLineAndColumn) {
  const auto f = find_invalid_utf8("0.2 pause\n0.6 note caf\xE9 spilled\n\xFF");
  ASSERT_TRUE(f);
  EXPECT_EQ(f->line, 2u);
  EXPECT_EQ(f->column, 13u);
  EXPECT_EQ(f->byte, 0xE9);
  // Counted from the line number a line-wise reader passes.
  const auto g = find_invalid_utf8("ab\x80", 7);
  ASSERT_TRUE(g);
  EXPECT_EQ(g->line, 7u);
  EXPECT_EQ(g->column, 3u);
}

TEST(Utf8, MalformedSequencesAreRefused) {
  for (const char* bad : {"\x80", "\xC0\xAF", "\xC1\xBF", "\xC3", "\xC3(", "\xE0\x80\xAF", "\xE2\x82",
                          "\xED\xA0\x80" /* a surrogate */, "\xF0\x80\x80\xAF", "\xF4\x90\x80\x80" /* > U+10FFFF */,
                          "\xF5\x80\x80\x80", "\xFE", "\xFF"})
    EXPECT_TRUE(find_invalid_utf8(bad)) << ::testing::PrintToString(std::string(bad));
}

TEST(Utf8, TheMessageNamesFileLineByteAndTheFix) {
  const auto f = find_invalid_utf8("ok\nnote caf\xE9\n");
  ASSERT_TRUE(f);
  EXPECT_EQ(curvlab::harness::utf8_fault_message("ops.txt", "the operator script", *f),
            "ops.txt:2: the operator script is not UTF-8 (byte 0xE9 at column 9); save the file as UTF-8");
}

}  // namespace
