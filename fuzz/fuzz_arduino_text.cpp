// The lab sketch's text: one line through parse_lab_line, the whole input as a PuTTY/Arduino
// file through read_arduino_text.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_check.hpp"
#include "spindown/arduino_text.hpp"
#include "spindown/lab_line.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spindown;
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  // The first line alone, as the serial bridge hands it over.
  const std::string_view first = text.substr(0, std::min(text.find('\n'), text.size()));
  const LabLine line = parse_lab_line(first);
  if (line.kind == LabLine::Kind::sample) {
    FUZZ_CHECK(line.millis >= 0);
    FUZZ_CHECK(std::isfinite(line.value));
  } else if (line.kind == LabLine::Kind::garbled) {
    FUZZ_CHECK(!line.why.empty());
  }

  ArduinoTextOptions options;
  options.max_line_reports = 5;
  options.drop_cut_first_line = size % 2 == 0;
  const Recording rec = read_arduino_text(text, "fuzz.tsv", options);
  fuzz::check_recording(rec);
  return 0;
}
