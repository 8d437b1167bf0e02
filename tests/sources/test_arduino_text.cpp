#include <gtest/gtest.h>

#include <fmt/format.h>
#include <fstream>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <fmt/format.h>

#include "diagnostic_queries.hpp"
#include "spindown/arduino_text.hpp"
#include "spindown/text_support.hpp"
#include "spindown/synthetic_run.hpp"

using namespace spindown;
using Severity = Diagnostic::Severity;

using namespace spindown::testing;

namespace {

const std::string data_dir = SPINDOWN_SAMPLE_DATA;


bool strictly_increasing(const std::vector<double>& t) {
  return std::adjacent_find(t.begin(), t.end(), [](double a, double b) { return b <= a; }) == t.end();
}

// "t\tv\r\n" lines from (ms, volts) pairs.
std::string lines(const std::vector<std::pair<long long, const char*>>& rows, const char* eol = "\r\n") {
  std::string s;
  for (const auto& [t, v] : rows) s += std::to_string(t) + "\t" + v + eol;
  return s;
}

std::string cadence(long long from_ms, int count, int step_ms = 20, const char* v = "1.00") {
  std::string s;
  for (int i = 0; i < count; ++i) s += std::to_string(from_ms + i * step_ms) + "\t" + v + "\r\n";
  return s;
}

}  // namespace

TEST(ArduinoText, EverySampleFileReadsCleanly) {
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(data_dir)) {
    if (entry.path().extension() != ".tsv") continue;
    ++files;
    const Recording r = read_arduino_text_file(entry.path().string());
    SCOPED_TRACE(entry.path().filename().string() + "\n" + all_diagnostics(r));
    EXPECT_FALSE(r.has_errors());
    ASSERT_GT(r.size(), 1000u);
    EXPECT_EQ(r.quantity, Quantity::back_emf_volts);
    EXPECT_EQ(r.t_s.size(), r.value.size());
    EXPECT_TRUE(strictly_increasing(r.t_s));
    EXPECT_TRUE(r.clock_restarts.empty());
    // The simulator's first sample is 0.5 s after boot. A PuTTY log's first line is the end of
    // the line before it ("0<TAB>0.00"): dropped as cut short.
    EXPECT_DOUBLE_EQ(r.t_s.front(), 0.5);
    EXPECT_EQ(mentions(r, "cut short"), mentions(r, "PuTTY log header"));
    EXPECT_EQ(r.lines_read, r.size() + r.lines_skipped);
    for (double v : r.value) ASSERT_TRUE(std::isfinite(v) && v > -1 && v < 6);
  }
  EXPECT_EQ(files, 7);
}

TEST(ArduinoText, SupplyLeadInReportsEachGarbledLine) {
  const Recording r = read_arduino_text_file(data_dir + "/supply-leadin.tsv");
  SCOPED_TRACE(all_diagnostics(r));
  std::ifstream tj(data_dir + "/supply-leadin.tsv.truth.json");
  const auto truth = nlohmann::json::parse(tj);
  const std::size_t garbage = truth.at("faults").at("garbage_lines"), samples = truth.at("samples");
  ASSERT_GE(garbage, 3u);
  // One warning per garbled line, naming the file and the line.
  const auto warnings = with(r, Severity::warning);
  ASSERT_EQ(warnings.size(), garbage);
  for (const auto* w : warnings) {
    EXPECT_NE(w->message.find("time is not a number; skipped"), std::string::npos) << w->message;
    EXPECT_NE(w->to_string().find(fmt::format("supply-leadin.tsv:{}: warning:", w->line)), std::string::npos);
  }
  // Every line: the header, the cut first line, the garbled lines, the samples.
  EXPECT_EQ(r.lines_read, samples + 2 + garbage);
  EXPECT_EQ(r.size(), samples);
  EXPECT_TRUE(mentions(r, "PuTTY log header"));
  EXPECT_NE(at_line(r, 1), nullptr);
  EXPECT_EQ(at_line(r, 1)->severity, Severity::note);
  // Reads the supply before the cut, then the coast.
  EXPECT_NEAR(r.value[0], truth.at("supply_v").get<double>(), 0.05);
  EXPECT_LT(r.value.back(), 0.05);
}

TEST(ArduinoText, SyntheticRunRoundTripsExactly) {
  SyntheticRunSpec spec;
  spec.lead_in = LeadIn::floating;
  spec.seed = 7;
  const SyntheticRun run = make_synthetic_run(spec);
  for (bool header : {false, true}) {
    const Recording r = read_arduino_text(to_arduino_text(run, 2, header), "synthetic");
    SCOPED_TRACE(all_diagnostics(r));
    EXPECT_TRUE(with(r, Severity::warning).empty());
    ASSERT_EQ(r.size(), run.t_ms.size());
    for (std::size_t i = 0; i < r.size(); ++i) {
      ASSERT_DOUBLE_EQ(r.t_s[i], run.t_ms[i] / 1000.0) << i;
      ASSERT_NEAR(r.value[i], run.volts[i], 1e-9) << i;
    }
  }
}

TEST(ArduinoText, EmptyFileIsAClearError) {
  const Recording r = read_arduino_text("", "empty.tsv");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(r.empty());
  EXPECT_EQ(r.diagnostics.front().message, "no samples: the file is empty");
}

TEST(ArduinoText, BinaryJunkIsAClearErrorWithoutAFloodOfWarnings) {
  std::mt19937 rng(3);
  std::string junk(100'000, '\0');
  for (auto& c : junk) c = static_cast<char>(rng());
  const Recording r = read_arduino_text(junk, "junk.bin");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(r.empty());
  EXPECT_EQ(r.diagnostics.size(), 1u);
  EXPECT_NE(r.diagnostics.front().message.find("no samples: binary data"), std::string::npos);

  const Recording nuls = read_arduino_text(std::string(4096, '\0'), "zeros.bin");
  ASSERT_TRUE(nuls.has_errors());
  EXPECT_NE(nuls.diagnostics.front().message.find("binary"), std::string::npos);
}

// More problem lines than are listed one by one: the summary gives the lowest and highest line
// not listed, whichever order they were found in (the cut first line's note comes after the
// parser's warnings), and how many of each kind.
TEST(ArduinoText, UnlistedProblemLinesAreSummarisedWithTheirRangeAndKinds) {
  std::string text = "3\t0.00\r\n";  // line 1: cut short (logging started mid-line)
  for (int i = 0; i < 200; ++i) {
    if (i >= 50 && i < 80) text += "garbled\r\n";  // lines 52 … 81
    else text += fmt::format("{}\t{:.2f}\r\n", 5234 + 20 * i, 1.0);
  }
  const Recording r = read_arduino_text(text, "many.tsv");
  const auto summary = std::find_if(r.diagnostics.begin(), r.diagnostics.end(), [](const Diagnostic& d) {
    return d.message.find("not listed one by one") != std::string::npos;
  });
  ASSERT_NE(summary, r.diagnostics.end());
  EXPECT_EQ(summary->message,
            "12 more problem lines not listed one by one (10 warnings, 2 notes; between lines 1 and 82); 32 in all");
}

TEST(ArduinoText, TextWithoutSamplesSaysWhy) {
  const Recording r = read_arduino_text("hello world\r\nthis is not data 1 2 3\r\n", "notes.txt");
  ASSERT_TRUE(r.has_errors());
  EXPECT_NE(r.diagnostics.back().message.find("no samples: none of the 2 lines"), std::string::npos)
      << all_diagnostics(r);
}

TEST(ArduinoText, OnlyZerosIsValidData) {
  const Recording r = read_arduino_text(cadence(1000, 50, 20, "0.00"), "zeros.tsv");
  EXPECT_FALSE(r.has_errors());
  EXPECT_EQ(r.size(), 50u);
  EXPECT_TRUE(std::all_of(r.value.begin(), r.value.end(), [](double v) { return v == 0; }));
}

TEST(ArduinoText, ThreeSamples) {
  const Recording r = read_arduino_text("100\t2.00\n120\t1.90\n140\t1.80\n", "three.tsv");
  EXPECT_FALSE(r.has_errors()) << all_diagnostics(r);
  ASSERT_EQ(r.size(), 3u);
  EXPECT_DOUBLE_EQ(r.t_s[2], 0.14);
  EXPECT_DOUBLE_EQ(r.value[2], 1.8);
}

TEST(ArduinoText, NanAndInfLinesAreWarnedAndSkipped) {
  std::string text = cadence(1000, 10);
  text += "1200\tnan\r\n1220\tinf\r\n";
  text += cadence(1240, 10);
  const Recording r = read_arduino_text(text, "nan.tsv");
  EXPECT_EQ(r.size(), 20u);
  ASSERT_NE(at_line(r, 11), nullptr);
  EXPECT_EQ(at_line(r, 11)->severity, Severity::warning);
  EXPECT_NE(at_line(r, 11)->message.find("NaN or infinite"), std::string::npos);
  ASSERT_NE(at_line(r, 12), nullptr);
  for (double v : r.value) EXPECT_TRUE(std::isfinite(v));
}

TEST(ArduinoText, ASampleGoingBackInTimeIsSkipped) {
  std::string text = cadence(1000, 10);   // lines 1-10: 1000 … 1180
  text += "1150\t1.00\r\n";               // line 11: back 30 ms
  text += cadence(1200, 10);              // lines 12-21
  const Recording r = read_arduino_text(text, "back.tsv");
  EXPECT_EQ(r.size(), 20u);
  EXPECT_TRUE(strictly_increasing(r.t_s));
  EXPECT_TRUE(r.clock_restarts.empty());
  ASSERT_NE(at_line(r, 11), nullptr) << all_diagnostics(r);
  EXPECT_EQ(at_line(r, 11)->severity, Severity::warning);
  EXPECT_NE(at_line(r, 11)->message.find("goes back"), std::string::npos);
}

TEST(ArduinoText, AGarbledTimeFarBackIsAnOutlierNotAReset) {
  // "27049" losing a digit: 2709 is far back, but the next line continues the old clock.
  std::string text = cadence(27000, 10, 20, "0.70");
  text += "2709\t0.70\r\n";  // line 11
  text += cadence(27200, 10, 20, "0.70");
  const Recording r = read_arduino_text(text, "digit.tsv");
  EXPECT_EQ(r.size(), 20u);
  EXPECT_TRUE(r.clock_restarts.empty());
  ASSERT_NE(at_line(r, 11), nullptr);
  EXPECT_EQ(at_line(r, 11)->severity, Severity::warning);
}

TEST(ArduinoText, AGarbledTimeFarAheadIsSkipped) {
  std::string text = cadence(27000, 10, 20, "0.70");
  text += "272000\t0.70\r\n";  // line 11: an extra digit
  text += cadence(27200, 10, 20, "0.70");
  const Recording r = read_arduino_text(text, "ahead.tsv");
  EXPECT_EQ(r.size(), 20u);
  EXPECT_TRUE(strictly_increasing(r.t_s));
  ASSERT_NE(at_line(r, 11), nullptr);
  EXPECT_NE(at_line(r, 11)->message.find("jumps ahead"), std::string::npos);
}

TEST(ArduinoText, ARealGapIsKeptAndNoted) {
  std::string text = cadence(1000, 10);
  text += cadence(60000, 10);  // the sketch paused for a minute
  const Recording r = read_arduino_text(text, "gap.tsv");
  EXPECT_EQ(r.size(), 20u);
  EXPECT_TRUE(with(r, Severity::warning).empty()) << all_diagnostics(r);
  EXPECT_TRUE(mentions(r, "no samples for"));
}

TEST(ArduinoText, DuplicateTimesAreSkipped) {
  std::string text = cadence(1000, 10);
  text += "1180\t1.00\r\n";  // line 11 repeats line 10
  text += cadence(1200, 5);
  const Recording r = read_arduino_text(text, "dup.tsv");
  EXPECT_EQ(r.size(), 15u);
  ASSERT_NE(at_line(r, 11), nullptr);
  EXPECT_NE(at_line(r, 11)->message.find("repeats line 10"), std::string::npos);
  EXPECT_TRUE(strictly_increasing(r.t_s));
}

TEST(ArduinoText, MillisWrapIsUnwrapped) {
  const long long top = 4294967296LL;
  std::string text = cadence(top - 200, 10);  // up to top - 20
  text += cadence(0, 10);                     // wrapped
  const Recording r = read_arduino_text(text, "wrap.tsv");
  ASSERT_EQ(r.size(), 20u) << all_diagnostics(r);
  EXPECT_TRUE(strictly_increasing(r.t_s));
  EXPECT_TRUE(r.clock_restarts.empty());
  EXPECT_DOUBLE_EQ(r.t_s[10], top / 1000.0);
  EXPECT_NEAR(r.t_s[10] - r.t_s[9], 0.020, 1e-9);
  EXPECT_TRUE(mentions(r, "wrapped"));
}

TEST(ArduinoText, ResetStartsANewTimeline) {
  std::string text = cadence(30000, 20);  // lines 1-20
  text += cadence(150, 20, 20, "0.50");   // lines 21-40: the Arduino rebooted
  const Recording r = read_arduino_text(text, "reset.tsv");
  ASSERT_EQ(r.size(), 40u);
  ASSERT_EQ(r.clock_restarts.size(), 1u);
  EXPECT_EQ(r.clock_restarts[0], 20u);
  EXPECT_DOUBLE_EQ(r.t_s[20], 0.150);
  ASSERT_NE(at_line(r, 21), nullptr);
  EXPECT_EQ(at_line(r, 21)->severity, Severity::note);
  EXPECT_NE(at_line(r, 21)->message.find("restarted"), std::string::npos);
  EXPECT_TRUE(with(r, Severity::warning).empty()) << all_diagnostics(r);
}

TEST(ArduinoText, NewPuttySessionMidFileWithCutLineAndReset) {
  std::string text = "=~=~=~=~ PuTTY log 2023.09.14 10:21:33 =~=~=~=~\r\n";
  text += "3\t0.00\r\n" + cadence(5234, 30);
  text += "=~=~=~=~ PuTTY log 2023.09.14 10:25:00 =~=~=~=~\r\n";  // line 33
  text += "1\t0.00\r\n" + cadence(2011, 30, 20, "2.00");              // line 34 cut, reset
  const Recording r = read_arduino_text(text, "sessions.tsv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 60u);
  ASSERT_EQ(r.clock_restarts.size(), 1u);
  EXPECT_EQ(r.clock_restarts[0], 30u);
  EXPECT_DOUBLE_EQ(r.t_s[30], 2.011);
  EXPECT_TRUE(with(r, Severity::warning).empty());
  ASSERT_NE(at_line(r, 34), nullptr);
  EXPECT_NE(at_line(r, 34)->message.find("cut short"), std::string::npos);
}

TEST(ArduinoText, AFirstLineThatFitsTheCadenceIsKept) {
  const Recording r = read_arduino_text(cadence(3, 20), "starts-at-3.tsv");
  EXPECT_EQ(r.size(), 20u);
  EXPECT_DOUBLE_EQ(r.t_s[0], 0.003);
  EXPECT_FALSE(mentions(r, "cut short"));
}

TEST(ArduinoText, GarbledFirstLineAndColumnHeaderAreNotes) {
  const Recording cut = read_arduino_text(".00\r\n" + cadence(1000, 10), "cut.tsv");
  EXPECT_EQ(cut.size(), 10u);
  ASSERT_NE(at_line(cut, 1), nullptr);
  EXPECT_EQ(at_line(cut, 1)->severity, Severity::note);

  const Recording header = read_arduino_text("millis\tvolts\r\n" + cadence(1000, 10), "header.tsv");
  EXPECT_EQ(header.size(), 10u);
  EXPECT_TRUE(with(header, Severity::warning).empty());
  EXPECT_TRUE(mentions(header, "column header"));
}

TEST(ArduinoText, LineEndingsLfCrLfAndCrOnlyGiveTheSameSamples) {
  const std::vector<std::pair<long long, const char*>> rows{{1000, "2.00"}, {1020, "1.90"}, {1040, "1.80"},
                                                            {1060, "1.70"}, {1080, "1.60"}};
  const Recording crlf = read_arduino_text(lines(rows, "\r\n"), "crlf");
  const Recording lf = read_arduino_text(lines(rows, "\n"), "lf");
  const Recording cr = read_arduino_text(lines(rows, "\r"), "cr");
  ASSERT_EQ(crlf.size(), 5u);
  EXPECT_EQ(lf.t_s, crlf.t_s);
  EXPECT_EQ(cr.t_s, crlf.t_s);
  EXPECT_EQ(cr.value, crlf.value);
  EXPECT_EQ(cr.lines_read, 5u);
  // No terminator on the last line.
  std::string no_eol = lines(rows, "\n");
  no_eol.pop_back();
  EXPECT_EQ(read_arduino_text(no_eol, "no-eol").size(), 5u);
}

TEST(ArduinoText, BlankLinesAreCounted) {
  const Recording r = read_arduino_text("\r\n1000\t1.00\r\n\r\n\r\n1020\t1.00\r\n1040\t1.00\r\n", "blank.tsv");
  EXPECT_EQ(r.size(), 3u);
  EXPECT_EQ(r.lines_read, 6u);
  EXPECT_EQ(r.lines_skipped, 3u);
  EXPECT_TRUE(mentions(r, "3 blank"));
}

TEST(ArduinoText, ManyBadLinesAreSummarised) {
  std::string text = cadence(1000, 5);
  for (int i = 0; i < 500; ++i) text += "garbage line\r\n";
  text += cadence(1100, 5);
  const Recording r = read_arduino_text(text, "bad.tsv");
  EXPECT_EQ(r.size(), 10u);
  const auto warnings = with(r, Severity::warning);
  ASSERT_EQ(warnings.size(), 21u);  // 20 listed + the summary
  EXPECT_EQ(warnings[0]->line, 6);
  EXPECT_EQ(warnings[20]->line, 0);
  EXPECT_NE(warnings[20]->message.find("480 more problem lines"), std::string::npos) << warnings[20]->message;
  EXPECT_NE(warnings[20]->message.find("(480 warnings; between lines 26 and 505)"), std::string::npos) << warnings[20]->message;
}

TEST(ArduinoText, TenMegabyteLineWithoutNewline) {
  const std::string huge(10'000'000, '5');
  const Recording alone = read_arduino_text(huge, "huge.tsv");
  ASSERT_TRUE(alone.has_errors());
  EXPECT_TRUE(alone.empty());

  const Recording mixed = read_arduino_text(cadence(1000, 10) + huge + "\r\n" + cadence(1200, 10), "mixed.tsv");
  EXPECT_EQ(mixed.size(), 20u);
  ASSERT_NE(at_line(mixed, 11), nullptr);
  EXPECT_NE(at_line(mixed, 11)->message.find("too long"), std::string::npos);
  EXPECT_LT(at_line(mixed, 11)->message.size(), 300u);  // the line is not copied into the message
}

TEST(ArduinoText, MissingFileNamesFileAndReason) {
  const Recording r = read_arduino_text_file("/nonexistent/dir/run.tsv");
  ASSERT_TRUE(r.has_errors());
  EXPECT_NE(r.diagnostics[0].message.find("/nonexistent/dir/run.tsv"), std::string::npos);
  EXPECT_NE(r.diagnostics[0].message.find("No such file or directory"), std::string::npos);
}

TEST(ArduinoText, OptionsValidate) {
  ArduinoTextOptions o;
  std::string why;
  EXPECT_TRUE(o.is_valid(&why));
  o.reset_min_back_s = -1;
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("reset_min_back_s"), std::string::npos);
  const Recording r = read_arduino_text(cadence(0, 5), "x", o);
  EXPECT_TRUE(r.has_errors());
}

// Found by tests/integration/hostile_inputs.sh: a line with Latin-1 bytes was quoted raw in its
// warning, and `spindown fit --json` then stopped with nlohmann::json's "invalid UTF-8" error.
// Bytes that are not UTF-8 are escaped; valid UTF-8 is kept and never cut inside a character.
TEST(ArduinoText, BytesThatAreNotUtf8AreEscapedInMessages) {
  std::string text = "1000\t2.50\r\n\xff\xfe\xc3\x28\t\xa0\r\n";
  text += std::string(38, 'a') + "\xc2\xb5\xc2\xb5 more\r\n";  // 'µ' at characters 39 and 40, then cut
  for (int i = 1; i < 40; ++i) text += std::to_string(1000 + 20 * i) + "\t2.50\r\n";
  const Recording r = read_arduino_text(text, "latin1.tsv");
  const Diagnostic* bad = at_line(r, 2);
  ASSERT_NE(bad, nullptr);
  EXPECT_NE(bad->message.find("\"\\xff\\xfe\\xc3(\\t\\xa0\""), std::string::npos) << bad->message;
  const Diagnostic* cut = at_line(r, 3);
  ASSERT_NE(cut, nullptr);
  EXPECT_NE(cut->message.find(std::string(38, 'a') + "\xc2\xb5\xc2\xb5\"…"), std::string::npos) << cut->message;
}

// Samples far into a file (many blocks of fast-path lines, mixed with lines the slow path takes)
// are quoted in messages by their own line's text and number.
TEST(ArduinoText, MessagesQuoteTheirOwnLineDeepInAFile) {
  std::string text = cadence(1000, 150, 20, "2.50");
  text += "  4000\t2.50\r\n";  // line 151: slow path (leading blanks), in order
  text += cadence(4020, 100, 20, "1.25");
  text += "6000\t7.77\n";      // line 252: repeats the time of line 251
  text += cadence(6020, 80, 20, "0.50");
  const Recording r = read_arduino_text(text, "deep.tsv");
  ASSERT_NE(at_line(r, 252), nullptr) << all_diagnostics(r);
  EXPECT_NE(at_line(r, 252)->message.find("\"6000\\t7.77\""), std::string::npos) << all_diagnostics(r);
  EXPECT_NE(at_line(r, 252)->message.find("line 251"), std::string::npos) << all_diagnostics(r);
  EXPECT_EQ(r.size(), 150u + 1 + 100 + 80);
  EXPECT_TRUE(strictly_increasing(r.t_s));
}

TEST(ArduinoText, TimelineProblemsDeepInLongBlocksAreFoundWhereTheyAre) {
  // build_timeline takes the usual steps in a tight loop: a problem anywhere in a block of 64
  // lines, at a block's first or last line or right after another, still gets the full checks.
  std::string text;
  std::vector<double> expected_ms;
  long long t = 5000;
  std::int64_t line = 0;
  std::vector<std::int64_t> skipped_lines;
  auto sample = [&](long long ms, bool kept) {
    text += std::to_string(ms) + "\t1.23\r\n";
    ++line;
    if (kept) expected_ms.push_back(static_cast<double>(ms));
    else skipped_lines.push_back(line);
  };
  for (int i = 1; i <= 400; ++i) {
    sample(t, true);
    if (i == 63 || i == 64 || i == 65 || i == 128 || i == 200 || i == 201) sample(t, false);  // repeats
    if (i == 100 || i == 300) sample(t - 40, false);                                           // back
    if (i == 150 || i == 250) sample(t + 100000, false);                                       // ahead
    t += 20;
  }
  const Recording r = read_arduino_text(text, "long.tsv");
  ASSERT_EQ(r.size(), expected_ms.size()) << all_diagnostics(r);
  for (std::size_t i = 0; i < expected_ms.size(); ++i) EXPECT_DOUBLE_EQ(r.t_s[i], expected_ms[i] / 1000) << i;
  for (const std::int64_t l : skipped_lines) {
    ASSERT_NE(at_line(r, l), nullptr) << l << "\n" << all_diagnostics(r);
    EXPECT_EQ(at_line(r, l)->severity, Severity::warning);
  }
  EXPECT_EQ(with(r, Severity::warning).size(), skipped_lines.size()) << all_diagnostics(r);
}

TEST(ArduinoText, BinaryVerdictIsTheFirst8KibsWhateverPathReadsThem) {
  // The reader counts control bytes only in what its slow path reads (the fast path's lines have
  // none): the verdict and its numbers must be those of the first 8 KiB as a whole.
  auto control_in_first_8k = [](const std::string& s) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < std::min<std::size_t>(s.size(), 8192); ++i) {
      const auto c = static_cast<unsigned char>(s[i]);
      n += (c < 0x20 || c == 0x7F) && c != '\t' && c != '\n' && c != '\r';
    }
    return n;
  };
  const std::string header = "=~=~=~=~ PuTTY log 2023.09.14 10:21:33 =~=~=~=~\r\n";
  for (const auto& [good_lines, junk_bytes, junk_char] :
       std::vector<std::tuple<int, std::size_t, char>>{{200, 6000, '\0'}, {600, 2000, '\x01'}, {700, 500, '\0'},
                                                      {700, 800, '\x7f'}, {900, 3000, '\0'}, {30, 100, '\0'}}) {
    std::string text = header + cadence(1000, good_lines);
    text += std::string(junk_bytes, junk_char) + "\r\n" + cadence(1000 + 20 * good_lines, 50);
    const std::size_t control = control_in_first_8k(text);
    const std::size_t looked = std::min<std::size_t>(text.size(), 8192);
    const Recording r = read_arduino_text(text, "mixed.txt");
    const bool binary = control * 10 > looked;
    SCOPED_TRACE(::testing::Message() << good_lines << " lines, " << junk_bytes << " junk: " << control << " of "
                                      << looked);
    if (binary) {
      ASSERT_EQ(r.diagnostics.size(), 1u) << all_diagnostics(r);
      EXPECT_EQ(r.diagnostics.front().message,
                "no samples: binary data, not Arduino text (" + std::to_string(control) + " of the first " +
                    std::to_string(looked) + " bytes are control characters or NUL)");
      EXPECT_TRUE(r.empty());
    } else {
      EXPECT_FALSE(mentions(r, "binary data")) << all_diagnostics(r);
      EXPECT_EQ(r.size(), static_cast<std::size_t>(good_lines + 50));
    }
  }
}

// A sketch that prints micros() instead of millis() (its delay(20) steps the clock by ~20,000):
// read as µs, with a warning naming the unit and the option for the other reading; a 1-Hz
// millis() log (steps of 1000) stays milliseconds.
TEST(ArduinoText, MicrosInsteadOfMillisIsReadAsMicroseconds) {
  std::string text;
  for (int i = 0; i < 100; ++i) text += std::to_string(13456788 + 20391 * i) + "\t2.50\r\n";
  const Recording r = read_arduino_text(text, "week.log");
  ASSERT_EQ(r.size(), 100u);
  EXPECT_NEAR(r.t_s[1] - r.t_s[0], 0.020391, 1e-9);
  bool said = false;
  for (const auto& d : r.diagnostics) said = said || (d.message.find("micros()") != std::string::npos &&
                                                      d.message.find("--time-unit ms") != std::string::npos);
  EXPECT_TRUE(said);
  const Recording slow = read_arduino_text(cadence(5000, 100, 1000), "slow.log");
  ASSERT_EQ(slow.size(), 100u);
  EXPECT_NEAR(slow.t_s[1] - slow.t_s[0], 1.0, 1e-9);
}

// Names students write in a shared capture belong to the runs after them; garbled bytes, headers,
// boot messages and readings are no names.
TEST(ArduinoText, NamesWrittenBetweenTheSamplesAreKeptWithTheSampleAfterThem) {
  using text::written_name;
  EXPECT_EQ(written_name("Ben\r"), "Ben");
  EXPECT_EQ(written_name("# Dmitri run 1"), "Dmitri");
  EXPECT_EQ(written_name("--- Chloé, 2nd try ---"), "Chloé");
  EXPECT_EQ(written_name("--- Chloe\xCC\x81 ---"), "Chloe\xCC\x81");  // decomposed, from a Mac's folder name
  EXPECT_EQ(written_name("Jürgen;"), "Jürgen");
  EXPECT_EQ(written_name("// Anna Lena Schmidt:"), "Anna Lena Schmidt");
  for (const char* no : {"millis\tvolts", "Zeit [ms];Spannung [V]", "Ready", "5234\t2.80", "volts", "\xf9\xd2\x86\xb6\xf1",
                         "ets Jun  8 2016 00:22:57", "x", "Time"})
    EXPECT_FALSE(written_name(no)) << no;
  const Recording r = read_arduino_text("0\t0.00\n20\t0.00\nBen\n40\t0.00\n60\t2.80\n# Chloé run 2\n80\t2.79\n", "names.txt");
  ASSERT_EQ(r.names.size(), 2u);
  EXPECT_EQ(r.names[0].name, "Ben");
  EXPECT_EQ(r.names[0].line, 3);
  EXPECT_EQ(r.name_before(3), "Ben");
  EXPECT_EQ(r.name_before(4), "Chloé");
  EXPECT_EQ(r.name_before(1), "");
  EXPECT_EQ(with(r, Severity::warning).size(), 0u);  // said as notes, not garbled lines
  // A third column of whose run it is: every sample read, each new name kept where it starts.
  const Recording c = read_arduino_text("0\t0.00\t\n20\t2.80\tŁukasz\n40\t2.79\tŁukasz\n60\t2.10\tZoë\n", "who.txt");
  EXPECT_EQ(c.size(), 4u);
  ASSERT_EQ(c.names.size(), 2u);
  EXPECT_EQ(c.name_before(2), "Łukasz");
  EXPECT_EQ(c.name_before(3), "Zoë");
  EXPECT_EQ(with(c, Severity::warning).size(), 0u);
}
