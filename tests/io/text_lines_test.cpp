#include "objmap/io/text_lines.h"

#include <gtest/gtest.h>

#include "objmap/core/error.h"
#include "support/test_support.h"

namespace objmap::io {
namespace {

using test::TempDir;
using test::write_text;

TEST(ParseDouble, AcceptsDecimalForms) {
  EXPECT_EQ(parse_double("1305031453.359684", "w", "t"), 1305031453.359684);
  EXPECT_EQ(parse_double("-0.5", "w", "t"), -0.5);
  EXPECT_EQ(parse_double("+2", "w", "t"), 2.0);
  EXPECT_EQ(parse_double("1e-3", "w", "t"), 1e-3);
  EXPECT_EQ(parse_double(".25", "w", "t"), 0.25);
}

TEST(ParseDouble, RejectsTextNanInfAndJunk) {
  for (const char* bad : {"abc", "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1.5x", "0x10",
                          "", "+-1", "1e999", "1,5"}) {
    try {
      parse_double(bad, "f.txt:3", "tx");
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "f.txt:3");
      EXPECT_NE(std::string(e.what()).find("tx is '"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("expected a finite number"), std::string::npos);
    }
  }
}

TEST(ParseInt, StrictIntegers) {
  EXPECT_EQ(parse_int("42", "w", "id"), 42);
  EXPECT_EQ(parse_int("-7", "w", "id"), -7);
  EXPECT_THROW(parse_int("4.2", "w", "id"), InputError);
  EXPECT_THROW(parse_int("x", "w", "id"), InputError);
  EXPECT_THROW(parse_int("99999999999999999999", "w", "id"), InputError);
}

TEST(SplitFields, SpacesTabsCommas) {
  EXPECT_EQ(split_fields("  1.0\t2,3 ,, 4  "), (std::vector<std::string>{"1.0", "2", "3", "4"}));
  EXPECT_TRUE(split_fields("   ").empty());
}

TEST(LineReader, SkipsCommentsAndBlanksKeepsLineNumbers) {
  TempDir dir;
  write_text(dir / "a.txt", "# file: 'x.bag'\n\n  # indented comment\n1 2 3\r\n\n4 five\n");
  LineReader in(dir / "a.txt");
  ASSERT_TRUE(in.next());
  EXPECT_EQ(in.line_number(), 4u);
  EXPECT_EQ(in.size(), 3u);
  EXPECT_EQ(in.field(2), "3");  // '\r' removed
  EXPECT_EQ(in.number(1, "b"), 2.0);
  ASSERT_TRUE(in.next());
  EXPECT_EQ(in.line_number(), 6u);
  EXPECT_EQ(in.where(), (dir / "a.txt").string() + ":6");
  try {
    in.number(1, "value");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              (dir / "a.txt").string() + ":6: value is 'five'; expected a finite number");
  }
  try {
    in.expect_fields(3, "a b c");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.reason(), "2 fields; expected 3: a b c");
  }
  EXPECT_FALSE(in.next());
  EXPECT_EQ(in.data_lines(), 2u);
  EXPECT_EQ(in.comments(), (std::vector<std::string>{"file: 'x.bag'", "indented comment"}));
}

TEST(LineReader, MissingFileAndFolder) {
  TempDir dir;
  EXPECT_THROW(LineReader(dir / "nope.txt"), InputError);
  EXPECT_THROW(LineReader(dir.path()), InputError);
}

}  // namespace
}  // namespace objmap::io
