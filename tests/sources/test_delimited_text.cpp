#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <string>

#include "spindown/delimited_text.hpp"
#include "spindown/synthetic_run.hpp"

using namespace spindown;
using Severity = Diagnostic::Severity;

namespace {

std::string all_diagnostics(const Recording& r) {
  std::string out;
  for (const auto& d : r.diagnostics) out += d.to_string() + "\n";
  return out;
}

bool mentions(const Recording& r, const std::string& text) {
  return std::any_of(r.diagnostics.begin(), r.diagnostics.end(),
                     [&](const Diagnostic& d) { return d.message.find(text) != std::string::npos; });
}

const Diagnostic* at_line(const Recording& r, std::int64_t line) {
  for (const auto& d : r.diagnostics)
    if (d.line == line) return &d;
  return nullptr;
}

std::size_t warnings(const Recording& r) {
  return std::count_if(r.diagnostics.begin(), r.diagnostics.end(),
                       [](const Diagnostic& d) { return d.severity == Severity::warning; });
}

// n rows of "t<sep>v" with t in seconds (printed with the given scale) and v = 3 - t.
std::string rows(int n, const char* sep, double scale = 1.0, int decimals = 3) {
  std::string s;
  for (int i = 0; i < n; ++i) {
    const double t = 0.02 * i;
    s += fmt::format("{:.{}f}{}{:.3f}\n", t * scale, decimals, sep, 3.0 - t);
  }
  return s;
}

}  // namespace

TEST(DelimitedText, CsvWithHeaderNamesAndUnits) {
  const Recording r = read_delimited_text("time (s),volts\n" + rows(100, ","), "run.csv");
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_FALSE(r.has_errors());
  ASSERT_EQ(r.size(), 100u);
  EXPECT_EQ(r.quantity, Quantity::back_emf_volts);
  EXPECT_NEAR(r.t_s[50], 1.0, 1e-12);
  EXPECT_NEAR(r.value[50], 2.0, 1e-12);
  EXPECT_EQ(warnings(r), 0u);
  EXPECT_TRUE(mentions(r, "time = column 1 'time (s)' in s (from the header)"));
}

TEST(DelimitedText, TsvMillisAndRpm) {
  std::string text = "millis\trpm\n";
  for (int i = 0; i < 50; ++i) text += fmt::format("{}\t{}\n", 1000 + 20 * i, 3000 - 10 * i);
  const Recording r = read_delimited_text(text, "run.tsv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 50u);
  EXPECT_EQ(r.quantity, Quantity::rpm);
  EXPECT_DOUBLE_EQ(r.t_s[1], 1.02);
  EXPECT_DOUBLE_EQ(r.value[1], 2990);
}

TEST(DelimitedText, WhitespaceSeparatedWithSuffixUnitsAndExtraColumns) {
  std::string text = "# bench 2, flywheel B\nindex  time_ms   omega_rad_s  current\n";
  for (int i = 0; i < 30; ++i) text += fmt::format("{}  {}  {:.2f}  0.1\n", i, 20 * i, 300.0 - i);
  DelimitedTextOptions o;
  o.value_column = "3";
  o.quantity = Quantity::rad_per_s;
  const Recording r = read_delimited_text(text, "run.txt", o);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 30u);
  EXPECT_EQ(r.quantity, Quantity::rad_per_s);
  EXPECT_DOUBLE_EQ(r.t_s[2], 0.04);
  EXPECT_DOUBLE_EQ(r.value[2], 298.0);
  EXPECT_TRUE(mentions(r, "'time_ms' in ms (from the header)"));
}

TEST(DelimitedText, SemicolonCsvWithDecimalComma) {
  std::string text = "Zeit [s];U [V]\n";
  for (int i = 0; i < 20; ++i) text += fmt::format("{},{:02d};2,{:02d}\n", i / 50, (i % 50) * 2, 99 - i);
  DelimitedTextOptions o;
  o.time_column = "1";
  const Recording r = read_delimited_text(text, "excel.csv", o);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 20u);
  EXPECT_DOUBLE_EQ(r.t_s[3], 0.06);
  EXPECT_DOUBLE_EQ(r.value[3], 2.96);
  EXPECT_EQ(r.quantity, Quantity::back_emf_volts);
}

// Google Sheets or LibreOffice in a German locale, saved as comma CSV: numbers quoted with a
// decimal comma ("6,010","2,65"). The quotes keep the fields apart; the comma in them is decimal.
// Before, every line was skipped ("time '0,0' is not a number") and no option helped.
TEST(DelimitedText, CommaCsvWithQuotedDecimalCommas) {
  std::string text = "\"Zeit\",\"Spannung\"\n";
  for (int i = 0; i < 20; ++i) text += fmt::format("\"{},{:03d}\",\"2,{:02d}\"\n", 6 + i / 50, (i % 50) * 20, 99 - i);
  const Recording r = read_delimited_text(text, "sheets.csv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 20u);
  EXPECT_DOUBLE_EQ(r.t_s[3], 6.06);
  EXPECT_DOUBLE_EQ(r.value[3], 2.96);
  // An English sheet's quoted points stay points.
  std::string en = "\"time\",\"volts\"\n";
  for (int i = 0; i < 20; ++i) en += fmt::format("\"{:.2f}\",\"2.{:02d}\"\n", 6 + 0.02 * i, 99 - i);
  const Recording e = read_delimited_text(en, "sheets-en.csv");
  ASSERT_EQ(e.size(), 20u);
  EXPECT_DOUBLE_EQ(e.value[3], 2.96);
}

TEST(DelimitedText, NoHeaderTwoColumnsInfersUnits) {
  const Recording ms = read_delimited_text(rows(40, ",", 1000, 0), "ms.csv");
  SCOPED_TRACE(all_diagnostics(ms));
  ASSERT_EQ(ms.size(), 40u);
  EXPECT_NEAR(ms.t_s[10], 0.2, 1e-12);
  EXPECT_TRUE(mentions(ms, "read as ms"));
  EXPECT_EQ(ms.quantity, Quantity::back_emf_volts);

  const Recording s = read_delimited_text(rows(40, " "), "s.txt");
  EXPECT_NEAR(s.t_s[10], 0.2, 1e-12);
  EXPECT_TRUE(mentions(s, "read as s"));

  const Recording us = read_delimited_text(rows(40, "\t", 1e6, 0), "us.tsv");
  EXPECT_NEAR(us.t_s[10], 0.2, 1e-12);
  EXPECT_TRUE(mentions(us, "read as us"));

  DelimitedTextOptions o;
  o.time_unit = TimeUnit::ms;
  const Recording given = read_delimited_text(rows(40, ","), "given.csv", o);  // 0.000, 0.020 … ms
  EXPECT_NEAR(given.t_s[10], 0.0002, 1e-15);
}

TEST(DelimitedText, AmbiguousColumnsAreAClearError) {
  const Recording r = read_delimited_text("time,millis,volts\n0,0,1\n1,1000,2\n", "two-times.csv");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(mentions(r, "'time' and 'millis' could each be the time")) << all_diagnostics(r);

  const Recording v = read_delimited_text("t,volts,rpm\n0,1,2\n1,1,2\n", "two-values.csv");
  ASSERT_TRUE(v.has_errors());
  EXPECT_TRUE(mentions(v, "could each be the value")) << all_diagnostics(v);

  const Recording none = read_delimited_text("a,b,c\n0,1,2\n1,1,2\n", "abc.csv");
  ASSERT_TRUE(none.has_errors());
  EXPECT_TRUE(mentions(none, "cannot tell which of the 3 columns is the time")) << all_diagnostics(none);

  const Recording unit = read_delimited_text("time,speed\n0,1\n1,2\n", "speed.csv");
  ASSERT_TRUE(unit.has_errors());
  EXPECT_TRUE(mentions(unit, "cannot tell the unit of value column 'speed'")) << all_diagnostics(unit);

  const Recording three = read_delimited_text("0,1,2\n1,1,2\n", "noheader3.csv");
  ASSERT_TRUE(three.has_errors());
}

TEST(DelimitedText, NamedColumnsResolveOrSayWhatExists) {
  const std::string text = "Time (ms),Speed [rpm],Temp\n0,100,20\n20,99,20\n40,98,20\n";
  DelimitedTextOptions o;
  o.time_column = "time";
  o.value_column = "speed";
  const Recording r = read_delimited_text(text, "named.csv", o);
  ASSERT_EQ(r.size(), 3u) << all_diagnostics(r);
  EXPECT_EQ(r.quantity, Quantity::rpm);
  EXPECT_DOUBLE_EQ(r.t_s[2], 0.04);

  o.value_column = "volts";
  const Recording bad = read_delimited_text(text, "named.csv", o);
  ASSERT_TRUE(bad.has_errors());
  EXPECT_TRUE(mentions(bad, "no column named 'volts' (columns: 1 'Time (ms)', 2 'Speed [rpm]', 3 'Temp')"))
      << all_diagnostics(bad);

  o.value_column = "7";
  EXPECT_TRUE(mentions(read_delimited_text(text, "named.csv", o), "column 7 does not exist"));
}

TEST(DelimitedText, BadRowsAreReportedWithLineNumbers) {
  std::string text = "t,v\n0,1\n0.02,1\n0.04,nan\n0.06\n0.08,abc\n0.10,inf\n,1\n0.12,1\n0.10,1\n0.14,1\n";
  const Recording r = read_delimited_text(text, "bad.csv");
  SCOPED_TRACE(all_diagnostics(r));
  EXPECT_EQ(r.size(), 4u);
  ASSERT_NE(at_line(r, 4), nullptr);
  EXPECT_NE(at_line(r, 4)->message.find("NaN or infinite"), std::string::npos);
  ASSERT_NE(at_line(r, 5), nullptr);
  EXPECT_NE(at_line(r, 5)->message.find("column 2 is missing"), std::string::npos);
  EXPECT_NE(at_line(r, 6)->message.find("not a number"), std::string::npos);
  EXPECT_NE(at_line(r, 8)->message.find("empty"), std::string::npos);
  ASSERT_NE(at_line(r, 10), nullptr);
  EXPECT_NE(at_line(r, 10)->message.find("goes back"), std::string::npos);
  EXPECT_EQ(r.lines_read, 11u);
  EXPECT_EQ(r.lines_skipped, 7u);
}

TEST(DelimitedText, EmptyBinaryAndHeaderOnly) {
  EXPECT_TRUE(mentions(read_delimited_text("", "e.csv"), "no samples: the file is empty"));
  EXPECT_TRUE(mentions(read_delimited_text(std::string(1000, '\0'), "z.csv"), "binary"));
  const Recording header_only = read_delimited_text("time,volts\n", "h.csv");
  EXPECT_TRUE(header_only.has_errors());
  EXPECT_TRUE(header_only.empty());
}

TEST(DelimitedText, SyntheticRunAsCsv) {
  const SyntheticRun run = make_synthetic_run(SyntheticRunSpec{});
  std::string csv = "time_s,emf_v\r\n";
  for (std::size_t i = 0; i < run.t_ms.size(); ++i) csv += fmt::format("{:.3f},{:.2f}\r\n", run.t_ms[i] / 1000, run.volts[i]);
  const Recording r = read_delimited_text(csv, "synthetic.csv");
  ASSERT_EQ(r.size(), run.t_ms.size()) << all_diagnostics(r);
  for (std::size_t i = 0; i < r.size(); ++i) {
    ASSERT_NEAR(r.t_s[i], run.t_ms[i] / 1000, 1e-9);
    ASSERT_NEAR(r.value[i], run.volts[i], 1e-9);
  }
}

TEST(DelimitedText, LongLineAndManyBadRowsStayBounded) {
  std::string text = "t,v\n0,1\n" + std::string(10'000'000, '9') + "\n0.02,1\n";
  for (int i = 0; i < 300; ++i) text += "x,y\n";
  text += "0.04,1\n";
  const Recording r = read_delimited_text(text, "long.csv");
  EXPECT_EQ(r.size(), 3u) << all_diagnostics(r);
  EXPECT_EQ(warnings(r), 21u);
  EXPECT_TRUE(mentions(r, "more problem lines"));
  for (const auto& d : r.diagnostics) EXPECT_LT(d.message.size(), 400u);
}

TEST(DelimitedText, OptionsValidate) {
  DelimitedTextOptions o;
  std::string why;
  EXPECT_TRUE(o.is_valid(&why));
  EXPECT_FALSE(o.names_columns());
  o.time_column = "0";
  EXPECT_FALSE(o.is_valid(&why));
  EXPECT_NE(why.find("between 1"), std::string::npos);
  o.time_column = "v";
  o.value_column = "V";
  EXPECT_FALSE(o.is_valid(&why));
  o = {};
  o.delimiter = '|';
  EXPECT_FALSE(o.is_valid(&why));
  o = {};
  o.quantity = Quantity::rpm;
  EXPECT_TRUE(o.names_columns());
}

TEST(DelimitedText, UnitsInTheHeaderInAnyDelimiterAndSpelling) {
  struct Case {
    const char* header;
    const char* sep;
    Quantity quantity;
    double scale;    // the value written is the reading divided by this
    double t_scale;  // the time written is seconds times this
  };
  const Case cases[] = {
      {"millis\trpm", "\t", Quantity::rpm, 1, 1000},
      {"time_ms\tspeed_rpm", "\t", Quantity::rpm, 1, 1000},
      {"t[ms];n[1/min]", ";", Quantity::rpm, 1, 1000},
      {"Zeit (s)\tDrehzahl (U/min)", "\t", Quantity::rpm, 1, 1},
      {"time,omega (rad/s)", ",", Quantity::rad_per_s, 1, 1000},
      {"ms speed(RPM)", " ", Quantity::rpm, 1, 1000},
      {"Time [s],Voltage [mV]", ",", Quantity::back_emf_volts, 1e-3, 1},
      {"t / s;n / (1/s)", ";", Quantity::rpm, 60, 1},
      {"Zeit in ms;Drehzahl in U/min", ";", Quantity::rpm, 1, 1000},
  };
  for (const Case& c : cases) {
    std::string text = std::string(c.header) + "\r\n";
    for (int i = 0; i < 60; ++i) {
      const double t = 0.02 * i, reading = 300.0 - 2 * i;
      text += (c.t_scale == 1 ? fmt::format("{:.3f}", t) : fmt::format("{}", std::lround(t * c.t_scale))) + c.sep +
              fmt::format("{:.12g}", reading / c.scale) + "\r\n";
    }
    const Recording r = read_delimited_text(text, "units.txt");
    SCOPED_TRACE(c.header);
    SCOPED_TRACE(all_diagnostics(r));
    ASSERT_EQ(r.size(), 60u);
    EXPECT_EQ(r.quantity, c.quantity);
    EXPECT_NEAR(r.t_s[10], 0.2, 1e-12);
    EXPECT_NEAR(r.value[10], 280.0, 1e-6);
  }
}

TEST(DelimitedText, AUnitRowUnderTheNames) {
  std::string text = "Zeit;Drehzahl\r\n[ms];[U/min]\r\n";
  for (int i = 0; i < 20; ++i) text += fmt::format("{};{}\r\n", 20 * i, 3000 - 10 * i);
  const Recording r = read_delimited_text(text, "units-row.csv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 20u);
  EXPECT_EQ(r.quantity, Quantity::rpm);
  EXPECT_DOUBLE_EQ(r.t_s[1], 0.02);
  EXPECT_TRUE(mentions(r, "1 units row"));
}

TEST(DelimitedText, AHeaderUnitSpindownCannotReadNamesTheOption) {
  const Recording kmh = read_delimited_text("t [s],Speed [km/h]\n0,1\n1,2\n", "kmh.csv");
  ASSERT_TRUE(kmh.has_errors());
  EXPECT_TRUE(mentions(kmh, "its unit 'km/h' is not one spindown reads")) << all_diagnostics(kmh);
  EXPECT_TRUE(mentions(kmh, "--value-unit rpm")) << all_diagnostics(kmh);
  const Recording speed = read_delimited_text("time,speed\n0,1\n1,2\n", "speed.csv");
  EXPECT_TRUE(mentions(speed, "cannot tell the unit of value column 'speed'")) << all_diagnostics(speed);
  EXPECT_TRUE(mentions(speed, "--value-unit rpm")) << all_diagnostics(speed);
  const Recording minutes = read_delimited_text("t [min],U [V]\n0,1\n1,2\n", "min.csv");
  EXPECT_TRUE(mentions(minutes, "its unit 'min' is not one spindown reads (s, ms, us)")) << all_diagnostics(minutes);
  // Given on the command line, the unit is used.
  DelimitedTextOptions o;
  o.quantity = Quantity::rpm;
  EXPECT_EQ(read_delimited_text("t [s],Speed [km/h]\n0,1\n1,2\n", "kmh.csv", o).size(), 2u);
}

TEST(DelimitedText, AQuotedHeaderWithACommaIsOneColumn) {
  std::string text = "\"Time, s\",\"RR_Wheel,Speed\",\"FL_Wheel,Speed\",\"Current, A\"\r\n";
  for (int i = 0; i < 30; ++i) text += fmt::format("{:.2f},{},{},0.5\r\n", 0.02 * i, 500 - i, 900 - i);
  DelimitedTextOptions o;
  o.value_column = "FL_Wheel,Speed";
  o.quantity = Quantity::rpm;
  const Recording r = read_delimited_text(text, "wheels.csv", o);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 30u);
  EXPECT_DOUBLE_EQ(r.value[0], 900);  // column 3, not shifted by the commas in the names
  EXPECT_TRUE(mentions(r, "value = column 3 'FL_Wheel,Speed'"));
  EXPECT_TRUE(mentions(r, "time = column 1 'Time, s' in s (from the header)"));
  // Not named: the two wheels are both speeds, and the error names them whole.
  const Recording both = read_delimited_text(text, "wheels.csv");
  EXPECT_TRUE(mentions(both, "'RR_Wheel,Speed' and 'FL_Wheel,Speed' could each be the value"))
      << all_diagnostics(both);
}

TEST(DelimitedText, NoHeaderProposesTheTimeAndTheSpeedColumns) {
  // A logger's CSV: time (s), speed (rpm), current (A), temperature; no names.
  std::string text;
  double w = 0;
  for (int i = 0; i < 1000; ++i) {
    const double t = 0.02 * i;
    if (t >= 1 && t < 6) w = 2800 * (1 - std::exp(-(t - 1) / 0.5));
    else if (t >= 6) w = std::max(0.0, w - 0.02 * (150 + 0.05 * w));
    const double current = t >= 1 && t < 6 ? 0.35 + 2.5 * std::exp(-(t - 1) / 0.3) : 0.0;
    text += fmt::format("{:.2f},{:.1f},{:.3f},{:.2f}\n", t, w, current, 24 + 0.01 * t);
  }
  const Recording r = read_delimited_text(text, "logger.csv");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(mentions(r, "the file has no header row")) << all_diagnostics(r);
  EXPECT_TRUE(mentions(r, "--time-column 1 --time-unit s --value-column 2 --value-unit rpm")) << all_diagnostics(r);
  EXPECT_FALSE(mentions(r, "4 '4'")) << all_diagnostics(r);  // no longer a list of every column
}

TEST(DelimitedText, ASpreadsheetsEmptyRowsAndDecimalCommasInTabText) {
  // Excel's "Unicode text" (decoded): tab-separated, decimal commas, rows of separators at the end.
  std::string text = "Zeit [s]\tU [V]\r\n";
  for (int i = 0; i < 20; ++i) text += fmt::format("0,{:02d}\t2,{:02d}\r\n", 2 * i, 90 - i);
  text += "\t\r\n\t\r\n;;;;\r\n";
  const Recording r = read_delimited_text(text, "excel.txt");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 20u);
  EXPECT_DOUBLE_EQ(r.value[3], 2.87);
  EXPECT_EQ(warnings(r), 0u);
  EXPECT_TRUE(mentions(r, "3 blank"));
}

TEST(DelimitedText, HeaderThatNeedsTheDelimitedReader) {
  EXPECT_TRUE(header_needs_delimited_reader("millis\trpm"));
  EXPECT_TRUE(header_needs_delimited_reader("time_ms\tspeed_rpm"));
  EXPECT_TRUE(header_needs_delimited_reader("Drehzahl [U/min]\tZeit [s]"));
  EXPECT_TRUE(header_needs_delimited_reader("millis\tVoltage [mV]"));
  EXPECT_TRUE(header_needs_delimited_reader("time\tspeed"));
  EXPECT_TRUE(header_needs_delimited_reader("t [s]\tvolts"));
  EXPECT_FALSE(header_needs_delimited_reader("millis\tvolts"));
  EXPECT_FALSE(header_needs_delimited_reader("time\tV"));
  EXPECT_FALSE(header_needs_delimited_reader("5234\t2.45"));
  EXPECT_FALSE(header_needs_delimited_reader("rpm"));
}

// A dyno's log as another lab's repository keeps it (blank-separated, nine columns, no names):
// the logger started mid-line, so the first line holds only the last three fields of a row, and
// the recording starts and ends mid-coast with a 1.8 s pause. The first line does not set the
// table's width (it is skipped and said), and the proposal names the clock (column 6, ms) and the
// falling speed (column 4, rpm) although the coast neither starts at a peak nor ends at rest (column
// 8, a quantity in proportion to it, is rougher, as in the real file).
TEST(DelimitedText, ACutFirstLineAndACoastUnderWayStillGetTheirColumns) {
  std::string text = "0.00 884.973 3612.600\n";
  double rpm = 436.0;
  std::int64_t ms = 783072;
  for (int i = 0; i < 250; ++i) {
    ms += i == 4 ? 1807 : 20;  // the logger's pause
    rpm -= i == 4 ? 4.3 : 0.045;
    const double jitter = 0.06 * std::sin(1.7 * i);
    text += fmt::format("15.93 0.0375 0.5973 {:.2f} 4.00 {} 0.00 {:.3f} {:.3f}\n", rpm + jitter, ms,
                        2.03 * rpm + 0.6 * std::cos(0.9 * i), 3612.6 + 0.012 * i);
  }
  const Recording r = read_delimited_text(text, "dyno.txt");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(mentions(r, "3 fields where the rows below have 9: a line cut at the start")) << all_diagnostics(r);
  EXPECT_TRUE(mentions(r, "--time-column 6 --time-unit ms --value-column 4 --value-unit rpm")) << all_diagnostics(r);
  EXPECT_TRUE(mentions(r, "a coast under way")) << all_diagnostics(r);

  DelimitedTextOptions o;
  o.time_column = "6";
  o.value_column = "4";
  o.time_unit = TimeUnit::ms;
  o.quantity = Quantity::rpm;
  const Recording named = read_delimited_text(text, "dyno.txt", o);
  EXPECT_FALSE(named.has_errors()) << all_diagnostics(named);
  EXPECT_EQ(named.size(), 250u);
}

// With no column that falls as a coast does, the clock is still proposed.
TEST(DelimitedText, NoSpeedColumnFoundStillProposesTheClock) {
  std::string text;
  for (int i = 0; i < 100; ++i) text += fmt::format("{},{:.2f},{:.2f}\n", 1000 + 20 * i, 5 + std::sin(i), 3.0);
  const Recording r = read_delimited_text(text, "flat.csv");
  ASSERT_TRUE(r.has_errors());
  EXPECT_TRUE(mentions(r, "try --time-column 1 --time-unit ms and name the speed")) << all_diagnostics(r);
}

// A sketch that prints the volts alone at a known rate (the handout's delay(20)): with the period
// given, row k is at k periods; without it, the refusal names the option.
TEST(DelimitedText, ValuesAloneWithAGivenPeriod) {
  std::string text;
  for (int i = 0; i < 30; ++i) text += fmt::format("{:.2f}\r\n", 2.8 - 0.01 * i);
  const Recording refused = read_delimited_text(text, "volts.txt");
  EXPECT_TRUE(refused.empty());
  EXPECT_NE(all_diagnostics(refused).find("--period-ms 20"), std::string::npos) << all_diagnostics(refused);
  DelimitedTextOptions o;
  o.period_ms = 20;
  const Recording r = read_delimited_text(text, "volts.txt", o);
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 30u);
  EXPECT_DOUBLE_EQ(r.t_s[0], 0.0);
  EXPECT_DOUBLE_EQ(r.t_s[10], 0.2);
  EXPECT_DOUBLE_EQ(r.value[10], 2.7);
}

// An oscilloscope's "Save CSV": "X,CH1,Start,Increment," over "Sequence,Volt,-4.000000e+00,
// 2.000000e-02", rows "k,value,". Sample k is at Start + k·Increment s, read so. A column that
// only counts samples is never proposed as a clock (following "--time-column 1 --time-unit ms"
// made every rate 20x): the refusal asks for the period.
TEST(DelimitedText, AScopesStartAndIncrementTimeItsSamples) {
  std::string text = "X,CH1,Start,Increment,\nSequence,Volt,-4.000000e+00,2.000000e-02\n";
  for (int i = 0; i < 40; ++i) text += fmt::format("{},{:.2e},\n", i, i < 10 ? 0.0 : 2.8 - 0.01 * i);
  const Recording r = read_delimited_text(text, "scope.csv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 40u);
  EXPECT_NEAR(r.t_s[0], -4.0, 1e-12);
  EXPECT_NEAR(r.t_s[10], -3.8, 1e-12);
  EXPECT_EQ(r.quantity, Quantity::back_emf_volts);

  std::string index;
  for (int i = 0; i < 200; ++i) index += fmt::format("{},{:.2f}\n", i, i < 20 ? 0.0 : 2.8 * std::exp(-(i - 20) / 60.0));
  const Recording refused = read_delimited_text(index, "index.csv");
  EXPECT_TRUE(refused.empty());
  const std::string why = all_diagnostics(refused);
  EXPECT_NE(why.find("--period-ms"), std::string::npos) << why;
  EXPECT_EQ(why.find("--time-column 1"), std::string::npos) << why;
  DelimitedTextOptions o;
  o.period_ms = 20;
  o.value_column = "2";
  const Recording followed = read_delimited_text(index, "index.csv", o);
  ASSERT_EQ(followed.size(), 200u);
  EXPECT_NEAR(followed.t_s[50], 1.0, 1e-12);
}

// A capture with a header that names no units (CoolTerm, a logger's "t,a,b"): the column proposal
// carries every option that reading it needs, the value's unit too; followed, it reads the file
// (before, the next refusal asked for --value-unit).
TEST(DelimitedText, AProposalCarriesTheValueUnitTheHeaderDoesNotGive) {
  std::string text = "stamp,ch0,ch1\n";
  for (int i = 0; i < 200; ++i)
    text += fmt::format("{},{},{:.3f}\n", 1000 + 20 * i, 500 + (i % 7), i < 20 ? 0.0 : 2.8 * std::exp(-(i - 20) / 60.0));
  const Recording refused = read_delimited_text(text, "coolterm.csv");
  EXPECT_TRUE(refused.empty());
  const std::string why = all_diagnostics(refused);
  EXPECT_NE(why.find("--time-column 1 --time-unit ms --value-column 3 --value-unit V"), std::string::npos) << why;
  DelimitedTextOptions o;
  o.time_column = "1";
  o.time_unit = TimeUnit::ms;
  o.value_column = "3";
  o.quantity = Quantity::back_emf_volts;
  const Recording r = read_delimited_text(text, "coolterm.csv", o);
  EXPECT_EQ(r.size(), 200u) << all_diagnostics(r);
}

// micros() as a CSV's whole-µs time column wraps at 2^32 µs (71.6 min after the board's reset):
// unwrapped as the lab's millis() is, never taken for a reset. Seconds with fractions (a PC's
// logger) never wrap.
TEST(DelimitedText, MicrosWrappingInACsvIsUnwrapped) {
  std::string text = "micros,volts\n";
  const double wrap = 4294967296.0;
  for (int k = 0; k < 200; ++k) {
    const double t = std::fmod(wrap - 2'000'000.0 + 20'000.0 * k, wrap);
    text += fmt::format("{:.0f},{:.3f}\n", t, 2.8 - 0.005 * k);
  }
  const Recording r = read_delimited_text(text, "micros.csv");
  SCOPED_TRACE(all_diagnostics(r));
  ASSERT_EQ(r.size(), 200u);
  EXPECT_TRUE(r.clock_restarts.empty());
  for (std::size_t i = 1; i < r.size(); ++i) ASSERT_NEAR(r.t_s[i] - r.t_s[i - 1], 0.02, 1e-9) << i;
  EXPECT_TRUE(mentions(r, "wrapped"));
}
