#pragma once
// The lab sketch's output as a file: "millis<TAB>volts" lines, usually a PuTTY log (a
// "=~=~=~ PuTTY log … =~=~=~" header, the first data line possibly cut short). Reads the
// whole file in one go and parses it in place; every line not used as a sample is accounted
// for in the Recording's diagnostics.
#include <cstddef>
#include <string>
#include <string_view>

#include "spindown/recording.hpp"

namespace spindown {

struct ArduinoTextOptions {
  // Garbled or out-of-order lines reported one by one before only a count is given.
  std::size_t max_line_reports = 20;
  // A jump back in millis() larger than this (s), followed by samples that continue from the
  // new time, is an Arduino reset (a clock restart); a smaller one is a bad sample.
  double reset_min_back_s = 1.0;
  // Drop a session's first sample when its time does not fit the following cadence
  // (PuTTY started logging in the middle of a line).
  bool drop_cut_first_line = true;

  bool is_valid(std::string* why) const;
};

// Parses text (the whole file's bytes). source names it in diagnostics. Quantity is back-EMF
// volts; t_s = millis / 1000 on the file's own clock, unwrapped across millis() overflow.
// No samples (empty, binary, nothing parseable) gives an error diagnostic "no samples: …".
Recording read_arduino_text(std::string_view text, std::string source, const ArduinoTextOptions& options = {});

// Reads path; a file that cannot be read gives a Recording with an error naming it and why.
Recording read_arduino_text_file(const std::string& path, const ArduinoTextOptions& options = {});

}  // namespace spindown
