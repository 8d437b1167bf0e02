#pragma once
// The lab sketch's serial protocol: one sample per line, "millis<TAB>volts" (volts from
// Serial.println(float), two decimals), CR LF. A pure function so the file reader, the
// serial bridge and the fuzzer share one parser.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

namespace spindown {

struct LabLine {
  enum class Kind { sample, blank, garbled };
  Kind kind = Kind::garbled;
  std::int64_t millis = 0;  // device time as printed (ms), valid for Kind::sample
  double value = 0;         // the printed reading, finite, valid for Kind::sample
  std::string_view why;     // for Kind::garbled: what was wrong, in words (static storage)
};

// Parses one line without its terminator (a trailing CR is tolerated). Accepts a tab or
// other whitespace between the fields; rejects extra fields, non-numbers, negative times,
// NaN/inf and values outside what an Arduino can print.
LabLine parse_lab_line(std::string_view line);

// The file reader's fast path. When text starts with a sample line exactly as the sketch
// prints it ("<digits><TAB or space>[-]<digits>[.<digits>]" followed by CR, LF or the end of
// text), sets sample to what parse_lab_line would give for that line and returns the line's
// length without its terminator. Returns 0 for anything else (leave it to parse_lab_line).
// It never looks past the line's terminator.
std::size_t parse_printed_sample(std::string_view text, LabLine& sample);

// The fast path over many lines at once: parses up to max_lines consecutive lines from the start
// of text while each is a sample line as parse_printed_sample takes it, appending its millis and
// value to the two vectors. Returns how many lines it took and their bytes, terminators included
// (a CR LF pair is one terminator), so text.substr(bytes) starts the first line it did not take.
struct PrintedLines {
  std::size_t lines = 0;
  std::size_t bytes = 0;
};
PrintedLines parse_printed_lines(std::string_view text, std::size_t max_lines, std::vector<double>& millis,
                                 std::vector<double>& values);

}  // namespace spindown
