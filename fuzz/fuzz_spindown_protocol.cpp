// The spindown-v1 firmware protocol: the input as one line through parse_spindown_line (what
// parses must print back identically), then as a serial byte stream through the bridge's path:
// LineSplitter, and each line to the spindown-v1 or the lab parser as the bridge chooses, then
// as a file (a PuTTY capture of the port) through read_spindown_text.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz_check.hpp"
#include "spindown/lab_line.hpp"
#include "spindown/line_splitter.hpp"
#include "spindown/spindown_protocol.hpp"
#include "spindown/spindown_text.hpp"

namespace {

std::string_view without_terminator(std::string_view s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace spindown;
  const std::string_view text(reinterpret_cast<const char*>(data), size);

  const SpindownLine line = parse_spindown_line(text);
  switch (line.kind) {
    case SpindownLine::Kind::sample: {
      FUZZ_CHECK(line.adc >= 0 && line.adc <= 65535);
      const std::string again = format_spindown_sample(line.seq, line.time_us, line.adc);
      const SpindownLine back = parse_spindown_line(without_terminator(again));
      FUZZ_CHECK(back.kind == SpindownLine::Kind::sample);
      FUZZ_CHECK(back.seq == line.seq && back.time_us == line.time_us && back.adc == line.adc);
      break;
    }
    case SpindownLine::Kind::banner: {
      FUZZ_CHECK(std::isfinite(line.banner.volts_per_count()));
      const std::string again = format_spindown_banner(line.banner);
      const SpindownLine back = parse_spindown_line(without_terminator(again));
      FUZZ_CHECK(back.kind == SpindownLine::Kind::banner);
      FUZZ_CHECK(back.banner.firmware == line.banner.firmware && back.banner.version == line.banner.version);
      FUZZ_CHECK(back.banner.adc_bits == line.banner.adc_bits && back.banner.period_us == line.banner.period_us);
      FUZZ_CHECK(back.banner.baud == line.banner.baud);
      break;
    }
    case SpindownLine::Kind::note:
      FUZZ_CHECK(line.text.data() >= text.data() && line.text.data() + line.text.size() <= text.data() + size);
      break;
    case SpindownLine::Kind::garbled: FUZZ_CHECK(!line.why.empty()); break;
    case SpindownLine::Kind::blank: break;
  }
  (void)spindown_crc8(text);

  // The bridge's path, in chunks of a size taken from the input.
  LineSplitter splitter(64 + (size > 0 ? data[0] : 0));
  const std::size_t chunk = 1 + (size > 1 ? data[1] % 17 : 0);
  std::uint64_t handed_out = 0;
  for (std::size_t at = 0; at < size; at += chunk) {
    splitter.feed(text.substr(at, chunk), [&](const LineSplitter::Line& l) {
      ++handed_out;
      FUZZ_CHECK(l.text.size() <= splitter.max_line_bytes());
      if (l.oversize) return;
      if (looks_like_spindown_line(l.text)) {
        (void)parse_spindown_line(l.text);
      } else {
        const LabLine lab = parse_lab_line(l.text);
        if (lab.kind == LabLine::Kind::sample) FUZZ_CHECK(std::isfinite(lab.value) && lab.millis >= 0);
      }
    });
  }
  FUZZ_CHECK(splitter.buffered() <= splitter.max_line_bytes());
  FUZZ_CHECK(handed_out == splitter.lines() + splitter.oversize_lines());

  // The whole input as a capture saved from the port.
  SpindownTextOptions options;
  options.max_line_reports = 5;
  std::int64_t lost = -1;
  const Recording rec = read_spindown_text(text, "fuzz.log", options, &lost);
  fuzz::check_recording(rec);
  FUZZ_CHECK(lost >= 0);
  FUZZ_CHECK(rec.lines_read == rec.size() + rec.lines_skipped);
  return 0;
}
