#pragma once
// A capture of the improved firmware's serial port as a file: spindown-v1 lines (banner,
// "S,<seq>,<micros>,<adc>*CC" samples, "#text*CC" notes; spindown_protocol.hpp), saved by PuTTY
// (its header, the first line possibly cut short), `cat` or a terminal, possibly ending mid-line.
// Reads the whole file in one go; every line not used as a sample is accounted for in the
// Recording's diagnostics.
//
// Values: the ADC count in volts by the banner in force (SpindownBanner::volts, the conversion
// the serial bridge uses; the protocol's defaults before any banner, with a warning). Time:
// micros() unwrapped by DeviceClock as the bridge does, so a capture gives the samples the bridge
// publishes. A clock restart (board reset: micros() going back other than by a 2^32 wrap, or a
// banner followed by a sequence number starting again) begins a new timeline
// (Recording::clock_restarts). A banner alone is no reset: the firmware also prints it after
// the `P` and `?` commands, its clock running on.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "spindown/recording.hpp"

namespace spindown {

struct SpindownTextOptions {
  // Garbled lines, sequence gaps and timeline problems reported one by one before only a count.
  std::size_t max_line_reports = 20;

  bool is_valid(std::string* why) const;
};

// Parses text (the whole file's bytes); source names it in diagnostics. Quantity is back-EMF
// volts; t_s = unwrapped micros / 10^6 on the board's own clock. Samples missing in sequence
// gaps are warnings naming the lines, and their total goes to *samples_lost when given. No
// samples (empty, binary, nothing parseable) gives an error diagnostic "no samples: …".
Recording read_spindown_text(std::string_view text, std::string source, const SpindownTextOptions& options = {},
                             std::int64_t* samples_lost = nullptr);

// Reads path; a file that cannot be read gives a Recording with an error naming it and why.
Recording read_spindown_text_file(const std::string& path, const SpindownTextOptions& options = {});

}  // namespace spindown
