#include "spindown/spindown_text.hpp"

#include <fmt/format.h>

#include "spindown/device_clock.hpp"
#include "spindown/spindown_protocol.hpp"
#include "spindown/text_support.hpp"

namespace spindown {

bool SpindownTextOptions::is_valid(std::string* why) const {
  if (max_line_reports == 0) {
    if (why) *why = "max_line_reports must be at least 1";
    return false;
  }
  return true;
}

namespace {

bool is_putty_header(std::string_view line) { return line.starts_with("=~=~=~"); }

// "spindown-coast 1.0.0, 10-bit ADC at 5.000 V full scale (4.888 mV per count), sample period
// 5000 µs, 115200 baud"
std::string describe(const SpindownBanner& b) {
  return fmt::format("{} {}, {}-bit ADC at {:.3f} V full scale ({:.3f} mV per count), sample period {} µs, {} baud",
                     text::escape_invalid_utf8(b.firmware), text::escape_invalid_utf8(b.version), b.adc_bits,
                     b.adc_ref_v, 1e3 * b.volts_per_count(), b.period_us, b.baud);
}

bool same_banner(const SpindownBanner& a, const SpindownBanner& b) {
  return a.firmware == b.firmware && a.version == b.version && a.adc_bits == b.adc_bits &&
         a.adc_ref_v == b.adc_ref_v && a.period_us == b.period_us && a.baud == b.baud;
}

}  // namespace

Recording read_spindown_text(std::string_view text, std::string source, const SpindownTextOptions& options,
                             std::int64_t* samples_lost) {
  using Severity = Diagnostic::Severity;
  if (samples_lost) *samples_lost = 0;
  Recording rec;
  rec.source = std::move(source);
  rec.quantity = Quantity::back_emf_volts;
  if (!text::readable_text(text, options, "spindown-v1 text", rec)) return rec;

  text::LineReporter reporter(rec, options.max_line_reports);
  // micros() as the bridge reads it: one tick a µs, wrapping at 2^32.
  DeviceClock clock(1);
  const SpindownBanner defaults{};
  SpindownBanner banner = defaults;  // the conversion in force
  bool banner_seen = false;
  bool banner_since_sample = false;  // a banner came after the last sample

  // The samples of the current clock epoch, turned into the Recording's timeline by the Arduino
  // reader's code when the epoch ends (their times already unwrapped: no wrap, no restart there).
  text::RawSamples raw(text);
  text::TimelineRules rules;
  rules.units_per_s = 1e6;
  rules.unit = "µs";
  rules.wrap = 0;
  rules.drop_cut_first = false;  // a cut line fails its checksum: never a sample
  text::TimelineCounts timeline;
  auto end_epoch = [&] {
    if (raw.size() == 0) return;
    if (!rec.empty()) rec.clock_restarts.push_back(rec.size());
    const text::TimelineCounts c = text::build_timeline(raw, rules, rec, reporter);
    timeline.cut_first += c.cut_first;
    timeline.backwards += c.backwards;
    timeline.ahead += c.ahead;
    timeline.duplicates += c.duplicates;
    timeline.gaps += c.gaps;
    raw = text::RawSamples(text);
  };

  std::size_t blank = 0, headers = 0, garbled = 0, cut = 0, banners = 0, notes = 0, before_banner = 0;
  std::int64_t lost = 0, first_before_banner = 0, first_bad_line = 0;
  std::string first_bad_why;
  bool first_content = true;  // the next non-blank line is the first of a logging session
  bool have_seq = false;      // last_seq is the previous sample's, in this clock epoch
  bool gaps_are_losses = false;  // no logging session began since that sample
  std::uint32_t last_seq = 0, last_time_us = 0;
  std::int64_t last_sample_line = 0;
  std::size_t garbled_since_sample = 0;  // garbled lines since the last sample, from this line
  std::int64_t first_garbled_since = 0;

  text::LineCursor cursor(text);
  while (!cursor.at_end()) {
    const std::string_view line = cursor.next_line();
    const std::int64_t n = cursor.line_number();
    if (is_putty_header(line)) {
      ++headers;
      rec.note(n, text::putty_header_note(line));
      first_content = true;
      gaps_are_losses = false;  // lines between two logging sessions were not logged, not lost
      continue;
    }
    const SpindownLine parsed = parse_spindown_line(line);
    if (parsed.kind == SpindownLine::Kind::blank) {
      ++blank;
      continue;
    }
    const bool first = first_content;
    first_content = false;
    std::string_view bad = parsed.why;
    std::string range;
    if (parsed.kind == SpindownLine::Kind::sample && parsed.adc > banner.max_count()) {
      range = fmt::format("ADC count {} above the {}-bit converter's range (0-{})", parsed.adc, banner.adc_bits,
                          banner.max_count());
      bad = range;
    }
    if (parsed.kind == SpindownLine::Kind::garbled || !range.empty()) {
      if (garbled_since_sample++ == 0) first_garbled_since = n;
      if (first_bad_line == 0) {
        first_bad_line = n;
        first_bad_why = bad;
      }
      const bool ends_file = cursor.at_end() && text.back() != '\n' && text.back() != '\r';
      ++(first || ends_file ? cut : garbled);
      if (first)
        reporter.report(Severity::note, n,
                        fmt::format("first line {} is not a sample ({}), probably cut short when logging started "
                                    "mid-line; skipped",
                                    text::quote_line(line), bad));
      else if (ends_file)
        reporter.report(Severity::note, n,
                        fmt::format("last line {} is cut short (the file ends mid-line: {}); skipped",
                                    text::quote_line(line), bad));
      else
        reporter.warn(n, fmt::format("{}: {}; skipped", text::quote_line(line), bad));
      continue;
    }
    if (parsed.kind == SpindownLine::Kind::note) {
      ++notes;
      reporter.report(Severity::note, n, fmt::format("firmware note {}", text::quote_line(parsed.text)));
      continue;
    }
    if (parsed.kind == SpindownLine::Kind::banner) {
      ++banners;
      if (!banner_seen)
        rec.note(n, "banner: " + describe(parsed.banner));
      else if (!same_banner(banner, parsed.banner))
        reporter.report(Severity::note, n, "new banner: " + describe(parsed.banner));
      banner = parsed.banner;
      banner_seen = banner_since_sample = true;
      continue;
    }

    // A sample. The firmware numbers samples from 0 at boot: after a banner, a sequence number
    // that does not go on from the last one is the board's reset, even if micros() went forward.
    const std::uint32_t ahead = parsed.seq - (last_seq + 1);  // modulo 2^32
    const bool seq_back = have_seq && parsed.seq != last_seq && ahead >= 0x80000000u;
    if (banner_since_sample && seq_back) clock.mark_reset();
    const DeviceClock::Reading r = clock.update(parsed.time_us);
    if (r.reset) {
      end_epoch();
      reporter.report(
          Severity::note, n,
          seq_back && banner_since_sample
              ? fmt::format("board reset: a banner, then the sequence starts again at {} (line {} had {}); a new "
                            "timeline starts here and no run spans it",
                            parsed.seq, last_sample_line, last_seq)
              : fmt::format("device clock restarted (board reset?): micros() goes back from {} µs (line {}) to {} "
                            "µs; a new timeline starts here and no run spans it",
                            last_time_us, last_sample_line, parsed.time_us));
      ++timeline.restarts;
      have_seq = false;
    } else if (r.wrapped) {
      ++timeline.wraps;
      reporter.report(Severity::note, n,
                      fmt::format("device clock wrapped from {} µs to {} µs (micros() overflow at 2^32 µs); "
                                  "unwrapped",
                                  last_time_us, parsed.time_us));
    }
    if (have_seq && parsed.seq != last_seq + 1) {
      if (parsed.seq == last_seq) {
        // The same line twice has the same time too: the timeline says so and skips it.
        if (parsed.time_us != last_time_us)
          reporter.warn(n, fmt::format("sequence number {} repeats line {} with another time ({} µs, then {} µs)",
                                       parsed.seq, last_sample_line, last_time_us, parsed.time_us));
      } else if (seq_back) {
        reporter.warn(n, fmt::format("sequence number goes back from {} (line {}) to {} (line {}) while the clock "
                                     "runs on",
                                     last_seq, last_sample_line, parsed.seq, n));
      } else if (gaps_are_losses) {
        lost += ahead;
        reporter.warn(n, fmt::format("sequence number jumps from {} (line {}) to {} (line {}): {} sample{} lost{}",
                                     last_seq, last_sample_line, parsed.seq, n, ahead, ahead == 1 ? "" : "s",
                                     garbled_since_sample == 0 ? std::string()
                                     : garbled_since_sample == 1
                                         ? fmt::format(" (line {} between was garbled)", first_garbled_since)
                                         : fmt::format(" ({} garbled lines between, from line {})",
                                                       garbled_since_sample, first_garbled_since)));
      }
    }
    have_seq = gaps_are_losses = true;
    banner_since_sample = false;
    garbled_since_sample = 0;
    last_seq = parsed.seq;
    last_time_us = parsed.time_us;
    last_sample_line = n;
    if (!banner_seen && before_banner++ == 0) first_before_banner = n;
    raw.add(n, line.data(), static_cast<double>(r.time_us), banner.volts(parsed.adc), raw.size() == 0);
  }
  end_epoch();
  const std::int64_t lines = cursor.line_number();
  if (before_banner > 0 && !rec.empty())
    rec.warn(first_before_banner,
             fmt::format("{} sample{} from this line on came before any banner: converted with the protocol's "
                         "defaults ({}-bit ADC at {:.3f} V full scale); the firmware prints its banner when it "
                         "starts, so the capture began after that",
                         before_banner, before_banner == 1 ? "" : "s", defaults.adc_bits, defaults.adc_ref_v));
  reporter.finish();
  text::sort_by_line(rec);
  if (samples_lost) *samples_lost = lost;

  rec.lines_read = static_cast<std::size_t>(lines);
  rec.lines_skipped = rec.lines_read - rec.size();
  if (rec.empty()) {
    if (first_bad_line > 0)
      rec.error(0, fmt::format("no samples: none of the {} lines is a spindown-v1 sample (line {}: {})", lines,
                               first_bad_line, first_bad_why));
    else
      rec.error(0, fmt::format("no samples: {} lines, {} blank, {} header lines, {} banners, {} firmware notes",
                               lines, blank, headers, banners, notes));
    return rec;
  }
  rec.note(0, text::summary_with_counts(fmt::format("{} spindown-v1 samples from {} lines", rec.size(), lines),
                                        {{headers, "PuTTY header"},
                                         {banners, "banner"},
                                         {notes, "firmware note"},
                                         {blank, "blank"},
                                         {cut, "cut short"},
                                         {garbled, "garbled"},
                                         {static_cast<std::size_t>(lost), "lost in sequence gaps"},
                                         {before_banner, "before any banner"}},
                                        timeline));
  return rec;
}

Recording read_spindown_text_file(const std::string& path, const SpindownTextOptions& options) {
  return text::read_text_file(path, options, [](std::string_view bytes, const std::string& source, const auto& o) {
    return read_spindown_text(bytes, source, o);
  });
}

}  // namespace spindown
