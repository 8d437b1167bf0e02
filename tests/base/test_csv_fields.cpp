// CsvFieldSplitter (csv_fields.hpp): RFC 4180's quoted fields — a delimiter inside quotes, doubled
// quotes, blanks around fields — for every delimiter spindown reads.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "spindown/csv_fields.hpp"

using namespace spindown;

namespace {

std::vector<std::string> fields(std::string_view line, char delimiter) {
  CsvFieldSplitter s;
  std::vector<std::string_view> out;
  s.split(line, delimiter, out);
  return {out.begin(), out.end()};
}

using Row = std::vector<std::string>;

}  // namespace

TEST(CsvFields, PlainFieldsTrimmed) {
  EXPECT_EQ(fields("a,b ,  c", ','), (Row{"a", "b", "c"}));
  EXPECT_EQ(fields("a,,b,", ','), (Row{"a", "", "b", ""}));
  EXPECT_EQ(fields("x;;;", ';'), (Row{"x", "", "", ""}));
  EXPECT_EQ(fields("1\t 2 \t3", '\t'), (Row{"1", "2", "3"}));
  EXPECT_EQ(fields("", ','), (Row{""}));
}

TEST(CsvFields, AQuotedHeaderWithACommaIsOneName) {
  EXPECT_EQ(fields(R"("Time, s","RR_Wheel,Speed","FL_Wheel,Speed",Current)", ','),
            (Row{"Time, s", "RR_Wheel,Speed", "FL_Wheel,Speed", "Current"}));
  // Doubled quotes are a quote; blanks outside the quotes go, inside they stay.
  EXPECT_EQ(fields(R"( "say ""hi""" , " padded " ,x)", ','), (Row{R"(say "hi")", " padded ", "x"}));
  EXPECT_EQ(fields(R"("";"a;b";"")", ';'), (Row{"", "a;b", ""}));
  // Tab-separated with a quoted tab.
  EXPECT_EQ(fields("\"a\tb\"\tc", '\t'), (Row{"a\tb", "c"}));
}

TEST(CsvFields, BlankSeparatedWithQuotedNames) {
  EXPECT_EQ(fields(R"x(  "time (s)"   "speed (rpm)"  current )x", ' '), (Row{"time (s)", "speed (rpm)", "current"}));
  EXPECT_EQ(fields("  1  2\t3  ", ' '), (Row{"1", "2", "3"}));
  EXPECT_TRUE(fields("   ", ' ').empty());
}

TEST(CsvFields, AnOpenQuoteTakesTheRestAndIsSaid) {
  CsvFieldSplitter s;
  std::vector<std::string_view> out;
  s.split(R"(a,"b,c)", ',', out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1], "b,c");
  EXPECT_TRUE(s.open_quote());
  s.split("a,b", ',', out);
  EXPECT_FALSE(s.open_quote());
}

TEST(CsvFields, ViewsStayValidAcrossFields) {
  // Many quoted fields with doubled quotes: every view must still read right at the end.
  std::string line;
  Row want;
  for (int i = 0; i < 200; ++i) {
    line += (i ? "," : "") + std::string("\"f\"\"") + std::to_string(i) + "\"";
    want.push_back("f\"" + std::to_string(i));
  }
  EXPECT_EQ(fields(line, ','), want);
}
