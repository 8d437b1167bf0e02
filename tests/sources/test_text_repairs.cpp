// repair_text (text_repairs.hpp): UTF-16, the Arduino IDE serial monitor's timestamps and a
// decimal comma, undone line for line, each said in a note; the lab's own text left alone.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "spindown/arduino_text.hpp"
#include "spindown/text_repairs.hpp"

using namespace spindown;

namespace {

const std::string lab = "=~=~= PuTTY log 2023.09.14 10:21:33 =~=~=\r\n0\t0.00\r\n20\t2.45\r\n40\t2.43\r\n60\t2.41\r\n"
                        "80\t2.40\r\n100\t2.38\r\n";

std::string utf16le(const std::string& ascii, bool bom) {
  std::string out = bom ? std::string("\xFF\xFE", 2) : std::string();
  for (char c : ascii) {
    out += c;
    out += '\0';
  }
  return out;
}

std::string utf16be(const std::string& ascii) {
  std::string out("\xFE\xFF", 2);
  for (char c : ascii) {
    out += '\0';
    out += c;
  }
  return out;
}

}  // namespace

TEST(TextRepairs, TheLabsOwnTextIsLeftAlone) {
  std::string text = lab;
  EXPECT_FALSE(needs_text_repair(text));
  EXPECT_TRUE(repair_text(text).empty());
  EXPECT_EQ(text, lab);
}

TEST(TextRepairs, Utf16WithAndWithoutByteOrderMark) {
  for (std::string text : {utf16le(lab, true), utf16le(lab, false), utf16be(lab)}) {
    ASSERT_TRUE(needs_text_repair(text));
    const auto notes = repair_text(text);
    ASSERT_EQ(notes.size(), 1u);
    EXPECT_NE(notes[0].find("UTF-16"), std::string::npos) << notes[0];
    EXPECT_EQ(text, lab);
  }
}

TEST(TextRepairs, Utf16BeyondAsciiBecomesUtf8) {
  // "Ω\n" and an emoji (a surrogate pair) in UTF-16LE with a mark.
  std::string text("\xFF\xFE\xA9\x03\x0A\x00\x3D\xD8\x00\xDE", 10);
  repair_text(text);
  EXPECT_EQ(text, "\xCE\xA9\n\xF0\x9F\x98\x80");
}

TEST(TextRepairs, SerialMonitorTimestampsAreRemovedLineForLine) {
  std::string text = "10:21:38.234 -> 0\t0.00\n10:21:38.254 -> 20\t2.45\n10:21:38.274 -> 40\t2.43\n"
                     "garbage line\n10:21:38.294 -> 60\t2.41";
  const auto notes = repair_text(text);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("removed from 4 lines"), std::string::npos) << notes[0];
  EXPECT_EQ(text, "0\t0.00\n20\t2.45\n40\t2.43\ngarbage line\n60\t2.41");
  const Recording rec = read_arduino_text(text, "ide.txt");
  EXPECT_EQ(rec.size(), 4u);
  EXPECT_DOUBLE_EQ(rec.value.at(1), 2.45);
}

TEST(TextRepairs, DecimalCommasOnlyWhenNoLineUsesAPoint) {
  std::string text = "0\t0,00\r\n20\t2,45\r\n40\t2,43\r\n60\t2,41\r\n80\t2,40\r\n100\t-0,01\r\n";
  const auto notes = repair_text(text);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("6 lines"), std::string::npos) << notes[0];
  EXPECT_EQ(text, "0\t0.00\r\n20\t2.45\r\n40\t2.43\r\n60\t2.41\r\n80\t2.40\r\n100\t-0.01\r\n");

  std::string mixed = "0\t0,00\n20\t2,45\n40\t2,43\n60\t2,41\n80\t2,40\n100\t2.38\n";
  EXPECT_FALSE(needs_text_repair(mixed));  // a point somewhere: the commas are not decimal commas
}

TEST(TextRepairs, TimestampsAndCommasTogether) {
  std::string text;
  for (int i = 0; i < 6; ++i) text += "10:21:38.2" + std::to_string(10 + i) + " -> " + std::to_string(20 * i) + "\t2,4" +
                                      std::to_string(i) + "\n";
  EXPECT_EQ(repair_text(text).size(), 2u);
  EXPECT_EQ(text.substr(0, 14), "0\t2.40\n20\t2.41");
}

// A pyserial script's print(ser.readline()) writes each line as a Python bytes literal: unwrapped
// and unescaped line for line (the tab, the \xNN escapes), said in a note; the lab's reader then
// reads the samples.
TEST(TextRepairs, PythonBytesLiteralsAreUnwrapped) {
  std::string text = "b'11\\t0.00\\r\\n'\nb'48231\\t0.00\\r\\n'\nb'48251\\t2.80\\r\\n'\r\nb\"48272\\t2.79\\r\\n\"\n"
                     "b'48292\\t2.78\\r\\n'\nb'\\xb0C\\t\\\\ok'\n";
  ASSERT_TRUE(needs_text_repair(text));
  const auto notes = repair_text(text);
  EXPECT_EQ(text, "11\t0.00\n48231\t0.00\n48251\t2.80\n48272\t2.79\n48292\t2.78\n\xb0" "C\t\\ok\n");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("Python bytes literals"), std::string::npos);
  EXPECT_NE(notes[0].find("6 lines"), std::string::npos);
  std::string lab_text = lab;
  EXPECT_FALSE(needs_text_repair(lab_text));
}

// Arduino IDE 2's Serial Monitor with "Show timestamp" on a sketch that prints the volts alone:
// the timestamp is the only time there is, so it becomes the time column (ms of the day), on
// across midnight. Before: "line 1 has 1 field".
TEST(TextRepairs, SerialMonitorTimestampsOfValuesAloneBecomeTheirTime) {
  std::string text = "23:59:59.950 -> 2.64\r\n23:59:59.970 -> 2.63\r\n23:59:59.990 -> 2.61\r\n"
                     "00:00:00.010 -> 2.60\r\n00:00:00.030 -> 2.58\r\n";
  ASSERT_TRUE(needs_text_repair(text));
  const auto notes = repair_text(text);
  EXPECT_EQ(text, "86399950\t2.64\r\n86399970\t2.63\r\n86399990\t2.61\r\n86400010\t2.60\r\n86400030\t2.58\r\n");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("is its time"), std::string::npos) << notes[0];
}

// The Arduino IDE's Serial Plotter labels ("millis:2020,volts:0.00"): a header of the labels and
// the values beneath it; a clock ("10:21:38") is no label.
TEST(TextRepairs, SerialPlotterLabelsBecomeAHeader) {
  std::string text = "millis:2020,volts:0.00\r\nmillis:2040,volts:2.80\r\nmillis:2060\tvolts:2.79\r\nmillis:2080 volts:2.78\r\n";
  ASSERT_TRUE(needs_text_repair(text));
  const auto notes = repair_text(text);
  EXPECT_EQ(text, "millis,volts\n2020,0.00\n2040,2.80\n2060,2.79\n2080,2.78\n");
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("Serial Plotter"), std::string::npos);
  std::string labels, values;
  EXPECT_FALSE(plotter_labels("10:21:38.234 -> 2.64", &labels, &values));
  EXPECT_FALSE(plotter_labels("5234\t2.80", &labels, &values));
}

// LabVIEW's "Write to Measurement File" without X columns: the readings alone, their period in the
// channel header (Delta_X). Each reading gets X0 + k·Delta_X; every line stays where it was.
TEST(TextRepairs, ALabViewMeasurementFileGetsItsTimesFromItsHeader) {
  std::string text =
      "LabVIEW Measurement\t\r\nWriter_Version\t2\r\nSeparator\tTab\r\nDecimal_Separator\t.\r\nX_Columns\tNo\r\n"
      "***End_of_Header***\t\r\n\t\r\nChannels\t1\t\r\nY_Unit_Label\tVolts\t\r\nX0\t0.0000000000000000E+0\t\r\n"
      "Delta_X\t0.010000\t\r\n***End_of_Header***\t\r\nVoltage\tComment\r\n2.450000\t\r\n2.440000\t\r\n2.430000\t\r\n";
  const std::size_t lines = std::count(text.begin(), text.end(), '\n');
  ASSERT_TRUE(needs_text_repair(text));
  const auto notes = repair_text(text);
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("Delta_X 0.01 s"), std::string::npos) << notes[0];
  EXPECT_EQ(std::size_t(std::count(text.begin(), text.end(), '\n')), lines);
  EXPECT_NE(text.find("t_s\tVoltage_V\n0\t2.450000\n0.01\t2.440000\n0.02\t2.430000\n"), std::string::npos) << text;
  // With a decimal comma it is left to the readers (which say why they cannot read it).
  std::string comma = "LabVIEW Measurement\t\nDecimal_Separator\t,\n***End_of_Header***\t\nDelta_X\t0,01\n***End_of_Header***\t\nVoltage\n2,45\n";
  EXPECT_TRUE(repair_text(comma).empty());
}
