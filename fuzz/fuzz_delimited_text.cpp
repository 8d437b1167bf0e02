// Delimited text (CSV, semicolon CSV, TSV, blanks) through read_delimited_text. The first byte
// picks the options (delimiter, header, time unit, named columns) so every combination is
// fuzzed; the rest is the file.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fuzz_check.hpp"
#include "spindown/delimited_text.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spindown;
  if (size == 0) return 0;
  const unsigned pick = data[0];
  const std::string_view text(reinterpret_cast<const char*>(data) + 1, size - 1);

  DelimitedTextOptions options;
  constexpr char delimiters[] = {0, ',', ';', '\t', ' '};
  options.delimiter = delimiters[pick % 5];
  switch ((pick / 5) % 3) {
    case 1: options.header = true; break;
    case 2: options.header = false; break;
    default: break;
  }
  switch ((pick / 15) % 4) {
    case 1: options.time_unit = TimeUnit::s; break;
    case 2: options.time_unit = TimeUnit::ms; break;
    case 3: options.time_unit = TimeUnit::us; break;
    default: break;
  }
  if ((pick / 60) % 2 == 1) {
    options.time_column = "1";
    options.value_column = "2";
  }
  options.max_line_reports = 5;
  if (!options.is_valid(nullptr)) return 0;

  const Recording rec = read_delimited_text(text, "fuzz.csv", options);
  fuzz::check_recording(rec);
  return 0;
}
