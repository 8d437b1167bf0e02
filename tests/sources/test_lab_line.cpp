#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <vector>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "spindown/lab_line.hpp"

using namespace spindown;
using Kind = LabLine::Kind;

TEST(LabLine, ParsesTheSketchsLine) {
  const LabLine l = parse_lab_line("8245\t2.81");
  ASSERT_EQ(l.kind, Kind::sample) << l.why;
  EXPECT_EQ(l.millis, 8245);
  EXPECT_DOUBLE_EQ(l.value, 2.81);
}

TEST(LabLine, ToleratesCarriageReturnAndOtherBlanks) {
  for (const char* s : {"8245\t2.81\r", "8245 2.81", "  8245\t\t2.81  \r", "8245\t2.81\r\r"}) {
    const LabLine l = parse_lab_line(s);
    ASSERT_EQ(l.kind, Kind::sample) << s << ": " << l.why;
    EXPECT_EQ(l.millis, 8245);
    EXPECT_DOUBLE_EQ(l.value, 2.81);
  }
}

TEST(LabLine, AcceptsNegativeAndZeroValuesAndTheLargestMillis) {
  EXPECT_DOUBLE_EQ(parse_lab_line("0\t-0.01").value, -0.01);
  EXPECT_EQ(parse_lab_line("0\t0.00").kind, Kind::sample);
  const LabLine top = parse_lab_line("4294967295\t0.00");
  ASSERT_EQ(top.kind, Kind::sample);
  EXPECT_EQ(top.millis, 4294967295LL);
  EXPECT_EQ(parse_lab_line("5234\t3").kind, Kind::sample);  // Serial.println(int)
}

TEST(LabLine, BlankLines) {
  for (const char* s : {"", "\r", "  \t ", "\r\r"}) EXPECT_EQ(parse_lab_line(s).kind, Kind::blank) << '"' << s << '"';
}

struct Bad {
  const char* line;
  const char* why_contains;
};

class LabLineRejects : public ::testing::TestWithParam<Bad> {};

TEST_P(LabLineRejects, WithAReason) {
  const LabLine l = parse_lab_line(GetParam().line);
  EXPECT_EQ(l.kind, Kind::garbled) << GetParam().line;
  EXPECT_NE(std::string(l.why).find(GetParam().why_contains), std::string::npos)
      << "line \"" << GetParam().line << "\" why: " << l.why;
}

INSTANTIATE_TEST_SUITE_P(
    Garbage, LabLineRejects,
    ::testing::Values(Bad{"6", "missing value"}, Bad{"6\r", "missing value"}, Bad{"38017\t", "missing value"},
                      Bad{"8245\t2.81\t7", "extra field"}, Bad{"8245 2.81 x", "extra field"},
                      Bad{"abc\t2.81", "time is not a number"}, Bad{"8245\tabc", "value is not a number"},
                      Bad{"8245\t2.8x", "value is not a number"}, Bad{"82a5\t2.81", "time is not a number"},
                      Bad{"-5\t2.81", "negative time"}, Bad{"12.5\t2.81", "whole number"},
                      Bad{"8245\tnan", "NaN or infinite"}, Bad{"8245\tinf", "NaN or infinite"},
                      Bad{"8245\t-inf", "NaN or infinite"}, Bad{"8245\tovf", "value is not a number"},
                      Bad{"4294967296\t1.00", "range of millis"}, Bad{"99999999999999999999999\t1", "range"},
                      Bad{"8245\t1e300", "larger than an Arduino"}, Bad{"8245\t1e999", "out of range"},
                      Bad{"8245,2.81", "time is not a number"}, Bad{"\t2.81", "whole number"},
                      Bad{"=~=~=~=~ PuTTY log 2023.09.14 =~=~", "not a number"},
                      Bad{"8245\t+2.81", "value is not a number"}));

TEST(LabLine, NulBytesAreGarbage) {
  const std::string with_nul("82\0" "45\t2.81", 8);
  EXPECT_EQ(parse_lab_line(with_nul).kind, Kind::garbled);
  const std::string value_nul("8245\t2.8\0" "1", 9);
  EXPECT_EQ(parse_lab_line(value_nul).kind, Kind::garbled);
}

TEST(LabLine, AVeryLongLineIsRejectedWithoutReadingIt) {
  const std::string digits(10'000'000, '7');
  const LabLine l = parse_lab_line(digits);
  EXPECT_EQ(l.kind, Kind::garbled);
  EXPECT_NE(std::string(l.why).find("too long"), std::string::npos);
}

TEST(LabLine, WhyIsEmptyForSamplesAndStaticForGarbage) {
  EXPECT_TRUE(parse_lab_line("1\t2").why.empty());
  std::string_view why;
  {
    std::string temp = "1\tx";
    why = parse_lab_line(temp).why;
  }
  EXPECT_EQ(why, "value is not a number");  // still valid after the input is gone
}

// Plain decimals take a fast path; it must give the very same double as from_chars, bit for bit,
// including the hardest cases (long fractions, halfway-looking digits, negative zero).
TEST(LabLine, PlainDecimalsMatchFromCharsBitForBit) {
  std::mt19937_64 rng(7);
  std::vector<std::string> values = {"0", "0.00", "-0.00", "5.00", "4.99", "0.1", "0.3", "2.675", "1.005",
                                     "123456789012345", "0.123456789012345", "999999999.999999", "1.", "-3.21"};
  for (int k = 0; k < 20000; ++k) {
    const int frac = static_cast<int>(rng() % 16);
    std::string digits = std::to_string(rng() % 1000000000000000ull);
    if (frac > 0 && frac < static_cast<int>(digits.size())) digits.insert(digits.size() - frac, ".");
    values.push_back((rng() % 2 ? "-" : "") + digits);
  }
  for (const std::string& v : values) {
    const LabLine l = parse_lab_line("1000\t" + v);
    double expected = 0;
    std::from_chars(v.data(), v.data() + v.size(), expected);
    if (std::fabs(expected) > 4294967040.0) {
      EXPECT_EQ(l.kind, Kind::garbled) << v;
      continue;
    }
    ASSERT_EQ(l.kind, Kind::sample) << v << ": " << l.why;
    EXPECT_EQ(std::memcmp(&l.value, &expected, sizeof expected), 0) << v << " read as " << l.value;
  }
}

// The file reader's fast path must give what parse_lab_line gives for every line it accepts,
// and take the line's whole length up to its terminator.
namespace {

void expect_fast_path_agrees(const std::string& line, const std::string& terminator) {
  const std::string text = line + terminator + "12345\t1.00\r\n12345\t1.00\r\n";  // enough text after it
  LabLine fast;
  const std::size_t length = parse_printed_sample(text, fast);
  if (length == 0) return;  // declined: the slow path judges it
  ASSERT_EQ(length, line.size()) << '"' << line << '"';
  const LabLine slow = parse_lab_line(line);
  ASSERT_EQ(slow.kind, Kind::sample) << '"' << line << "\": " << slow.why;
  EXPECT_EQ(fast.kind, Kind::sample);
  EXPECT_EQ(fast.millis, slow.millis) << '"' << line << '"';
  EXPECT_EQ(std::memcmp(&fast.value, &slow.value, sizeof(double)), 0) << '"' << line << "\" " << fast.value
                                                                         << " vs " << slow.value;
}

}  // namespace

TEST(LabLineFastPath, TakesTheSketchsLines) {
  LabLine l;
  EXPECT_EQ(parse_printed_sample("8245\t2.81\r\n8265\t2.80\r\n8285\t2.80\r\n", l), 9u);
  EXPECT_EQ(l.kind, Kind::sample);
  EXPECT_EQ(l.millis, 8245);
  EXPECT_EQ(l.value, 2.81);
  EXPECT_EQ(parse_printed_sample("0 -0.01\n8265\t2.80\r\n8285\t2.80\r\n", l), 7u);
  EXPECT_EQ(l.value, -0.01);
  EXPECT_TRUE(std::signbit(parse_printed_sample("0\t-0.00\n8265\t2.80\r\n8285\t2.80\r\n", l) ? l.value : 1.0));
}

TEST(LabLineFastPath, DeclinesWhatItDoesNotKnow) {
  LabLine l;
  for (const char* s : {"8245\t2.81",  // too little text left to read words safely
                        " 8245\t2.81\r\n8265\t2.80\r\n8285\t2.80\r\n", "-20\t1.00\r\n8265\t2.80\r\n8285\t2.80\r\n",
                        "12345678\t1.00\r\n8265\t2.80\r\n8285\t2.80\r\n", "5254\t2.8\t1.0\r\n8265\t2.80\r\n8285\t2.80\n",
                        "5254\t2.x8\r\n8265\t2.80\r\n8285\t2.80\r\n", "5254\tnan\r\n8265\t2.80\r\n8285\t2.80\r\n",
                        "5254\t1e3\r\n8265\t2.80\r\n8285\t2.80\r\n", "5254\t12345678\r\n8265\t2.80\r\n8285\t2.80\r\n",
                        "5254\t1234567.5\r\n8265\t2.80\r\n8285\t2.80\r\n", "5254\t2.81 \r\n8265\t2.80\r\n8285\t2.80\r\n",
                        "5254\t.\r\n8265\t2.80\r\n8285\t2.80\r\n", "5254\t-\r\n8265\t2.80\r\n8285\t2.80\r\n"})
    EXPECT_EQ(parse_printed_sample(s, l), 0u) << s;
}

TEST(LabLineFastPath, AgreesWithTheSlowPathOnRandomLines) {
  std::mt19937 rng(7);
  const std::string alphabet = "0123456789012345678901234567890123456789..--\t \vxe+";  // no terminators
  for (int i = 0; i < 200000; ++i) {
    std::string line;
    const int len = std::uniform_int_distribution<int>(0, 20)(rng);
    for (int k = 0; k < len; ++k) line += alphabet[std::uniform_int_distribution<std::size_t>(0, alphabet.size() - 1)(rng)];
    expect_fast_path_agrees(line, i % 2 ? "\r\n" : "\n");
    if (HasFatalFailure()) return;
  }
  // Shaped like the sketch's lines: every split of up to 7 digits around a point, signs, separators.
  for (int i = 0; i < 100000; ++i) {
    const auto digits = [&](int n) {
      std::string s;
      for (int k = 0; k < n; ++k) s += static_cast<char>('0' + std::uniform_int_distribution<int>(0, 9)(rng));
      return s;
    };
    std::string line = digits(std::uniform_int_distribution<int>(1, 9)(rng)) + (i % 3 ? "\t" : " ");
    if (i % 5 == 0) line += '-';
    line += digits(std::uniform_int_distribution<int>(0, 8)(rng));
    if (i % 4) line += '.' + digits(std::uniform_int_distribution<int>(0, 8)(rng));
    expect_fast_path_agrees(line, i % 2 ? "\r" : "\n");
    if (HasFatalFailure()) return;
  }
}

// The lines parse_printed_lines takes from text are exactly those parse_printed_sample takes one
// after another (the same numbers, bit for bit), each also what the general parser parse_lab_line
// gives, and it stops at the first it does not take (or at max_lines).
namespace {

void expect_many_lines_agree(const std::string& text, std::size_t max_lines) {
  std::vector<double> millis, values;
  const PrintedLines taken = parse_printed_lines(text, max_lines, millis, values);
  ASSERT_EQ(millis.size(), taken.lines);
  ASSERT_EQ(values.size(), taken.lines);
  std::string_view rest = text;
  std::size_t lines = 0;
  while (lines < max_lines) {
    LabLine one;
    const std::size_t length = parse_printed_sample(rest, one);
    if (length == 0) break;
    ASSERT_LT(lines, taken.lines) << text;
    EXPECT_EQ(static_cast<double>(one.millis), millis[lines]);
    EXPECT_EQ(std::memcmp(&one.value, &values[lines], sizeof(double)), 0);
    const LabLine general = parse_lab_line(rest.substr(0, length));
    ASSERT_EQ(general.kind, Kind::sample) << rest.substr(0, length);
    EXPECT_EQ(static_cast<double>(general.millis), millis[lines]) << rest.substr(0, length);
    EXPECT_EQ(std::memcmp(&general.value, &values[lines], sizeof(double)), 0)
        << rest.substr(0, length) << " read as " << values[lines];
    std::size_t next = length + 1;
    if (rest[length] == '\r' && next < rest.size() && rest[next] == '\n') ++next;
    rest.remove_prefix(next);
    ++lines;
  }
  ASSERT_EQ(lines, taken.lines) << text;
  EXPECT_EQ(taken.bytes, text.size() - rest.size());
}

}  // namespace


// The many-lines fast path takes exactly the lines parse_printed_sample takes, one after another,
// with the same numbers, and stops at the first it does not (or at max_lines).
TEST(LabLineFastPath, ManyLinesAgreeWithOneLineAtATime) {
  std::mt19937 rng(11);
  const char* shapes[] = {"%d\t%d.%02d", "%d %d.%02d", "%d\t-%d.%02d", "%d\t%d.%d", "%d\t%d", "%d\t%d.%02dx", " %d\t%d.%02d"};
  const char* endings[] = {"\r\n", "\n", "\r"};
  for (int round = 0; round < 2000; ++round) {
    std::string text;
    const int n = std::uniform_int_distribution<int>(0, 40)(rng);
    for (int k = 0; k < n; ++k) {
      char line[64];
      const char* shape = shapes[std::uniform_int_distribution<int>(0, round % 3 ? 1 : 6)(rng)];
      std::snprintf(line, sizeof line, shape, std::uniform_int_distribution<int>(0, 9999999)(rng),
                    std::uniform_int_distribution<int>(0, 99)(rng), std::uniform_int_distribution<int>(0, 99)(rng));
      text += line;
      text += endings[std::uniform_int_distribution<int>(0, 2)(rng)];
    }
    expect_many_lines_agree(text, round % 5 == 0 ? 7 : 64);
    if (HasFatalFailure()) return;
  }
}

// Long runs of lines printed alike (the shape fast path), each with a chance of one damaged byte:
// every line parse_printed_lines takes gives exactly what the general parser parse_lab_line gives
// (whose value is strtod-exact: PlainDecimalsMatchFromCharsBitForBit), and it takes the same
// lines and bytes as the one-line-at-a-time fast path. Lines it declines go to the reader's slow path.
TEST(LabLineFastPath, RunsOfAlikeLinesWithDamageAgreeWithTheGeneralParser) {
  std::mt19937 rng(23);
  const std::string damage = "0123456789 \t\r\n.-+eE0x\v";
  const char* endings[] = {"\r\n", "\n", "\r"};
  const char* odd_values[] = {"-0.00", "0.00", "-0.01", "00.50", "2.8", "2.800", "+2.80", "2.80e0", "1e2", "3.",
                              ".25", "-.25", "12.5", "-1.5", "1234", "0000000002.81", "123456789012345678",
                              "4294967040", "4294967041", "9.99", "10.00", "2.81 ", " 2.81", "2.81\t"};
  const char* odd_times[] = {"0", "00005000", "+5000", "-5000", "5000.0", "1e3", "4294967295", "4294967296",
                             "9999999", "10000000", "0000000", " 5000"};
  for (int round = 0; round < 3000; ++round) {
    std::string text;
    const int n = std::uniform_int_distribution<int>(0, 150)(rng);
    const char* ending = endings[std::uniform_int_distribution<int>(0, round % 4 ? 1 : 2)(rng)];
    const char separator = round % 7 == 0 ? ' ' : '\t';
    int t = std::uniform_int_distribution<int>(0, round % 3 ? 20000 : 9999900)(rng);
    for (int k = 0; k < n; ++k, t += 20) {
      std::string line = std::to_string(t) + separator;
      char value[16];
      std::snprintf(value, sizeof value, "%d.%02d", std::uniform_int_distribution<int>(0, 9)(rng),
                    std::uniform_int_distribution<int>(0, 99)(rng));
      line += value;
      const int odd = std::uniform_int_distribution<int>(0, 99)(rng);
      if (odd < 3) line = std::to_string(t) + separator + odd_values[std::uniform_int_distribution<std::size_t>(0, std::size(odd_values) - 1)(rng)];
      else if (odd < 5) line = odd_times[std::uniform_int_distribution<std::size_t>(0, std::size(odd_times) - 1)(rng)] + (separator + std::string(value));
      else if (odd < 7) line[std::uniform_int_distribution<std::size_t>(0, line.size() - 1)(rng)] = damage[std::uniform_int_distribution<std::size_t>(0, damage.size() - 1)(rng)];
      else if (odd < 8) line.insert(std::uniform_int_distribution<std::size_t>(0, line.size())(rng), 1, damage[std::uniform_int_distribution<std::size_t>(0, damage.size() - 1)(rng)]);
      else if (odd < 9) line.erase(std::uniform_int_distribution<std::size_t>(0, line.size() - 1)(rng), 1);
      text += line;
      text += odd == 9 ? endings[std::uniform_int_distribution<int>(0, 2)(rng)] : ending;
    }
    // As the reader calls it: a block of lines at a time, each call where the last one stopped
    // (past the line it declined, which the slow path takes).
    std::string_view rest = text;
    while (!rest.empty()) {
      expect_many_lines_agree(std::string(rest), round % 5 == 0 ? 7 : 64);
      if (HasFatalFailure()) return;
      std::vector<double> millis, values;
      const PrintedLines taken = parse_printed_lines(rest, round % 5 == 0 ? 7 : 64, millis, values);
      rest.remove_prefix(taken.bytes);
      const std::size_t nl = rest.find_first_of("\r\n");
      rest.remove_prefix(taken.lines > 0 || nl == std::string_view::npos ? 0 : nl + 1);
      if (taken.lines == 0 && nl == std::string_view::npos) break;
    }
  }
}
