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

namespace {

using Severity = Diagnostic::Severity;

// One spindown-v1 capture read line by line: PuTTY headers, banners (the conversion in force),
// firmware notes, garbled or cut lines, and samples with their sequence numbers and micros().
class SpindownReader {
 public:
  SpindownReader(std::string_view text, std::string source, const SpindownTextOptions& options)
      : text_(text), options_(options), reporter_(rec_, options.max_line_reports), raw_(text) {
    rec_.source = std::move(source);
    rec_.quantity = Quantity::back_emf_volts;
    rules_.units_per_s = 1e6;
    rules_.unit = "µs";
    rules_.wrap = 0;
    rules_.drop_cut_first = false;  // a cut line fails its checksum: never a sample
  }

  Recording read(std::int64_t* samples_lost) && {
    if (!text::readable_text(text_, options_, "spindown-v1 text", rec_)) return std::move(rec_);
    text::LineCursor cursor(text_);
    while (!cursor.at_end()) {
      const std::string_view line = cursor.next_line();
      read_line(line, cursor.line_number(), cursor.at_end());
    }
    end_epoch();
    finish(cursor.line_number());
    if (samples_lost) *samples_lost = lost_;
    return std::move(rec_);
  }

 private:
  void read_line(std::string_view line, std::int64_t n, bool last_line) {
    if (is_putty_header(line)) {
      ++headers_;
      rec_.note(n, text::putty_header_note(line));
      first_content_ = true;
      gaps_are_losses_ = false;  // lines between two logging sessions were not logged, not lost
      return;
    }
    const SpindownLine parsed = parse_spindown_line(line);
    if (parsed.kind == SpindownLine::Kind::blank) {
      ++blank_;
      return;
    }
    const bool first = first_content_;
    first_content_ = false;
    if (parsed.kind == SpindownLine::Kind::sample && parsed.adc > banner_.max_count()) {
      const std::string range = fmt::format("ADC count {} above the {}-bit converter's range (0-{})", parsed.adc,
                                            banner_.adc_bits, banner_.max_count());
      return bad_line(line, n, range, first, last_line);
    }
    switch (parsed.kind) {
      case SpindownLine::Kind::garbled: return bad_line(line, n, parsed.why, first, last_line);
      case SpindownLine::Kind::note:
        ++notes_;
        reporter_.report(Severity::note, n, fmt::format("firmware note {}", text::quote_line(parsed.text)));
        return;
      case SpindownLine::Kind::banner: return on_banner(parsed.banner, n);
      default: return on_sample(parsed, line, n);
    }
  }

  // A line that is no sample: the first of a session or the file's last (cut short) is a note,
  // any other a warning.
  void bad_line(std::string_view line, std::int64_t n, std::string_view bad, bool first, bool last_line) {
    if (garbled_since_sample_++ == 0) first_garbled_since_ = n;
    if (first_bad_line_ == 0) {
      first_bad_line_ = n;
      first_bad_why_ = bad;
    }
    const bool ends_file = last_line && text_.back() != '\n' && text_.back() != '\r';
    ++(first || ends_file ? cut_ : garbled_);
    if (first)
      reporter_.report(Severity::note, n,
                       fmt::format("first line {} is not a sample ({}), probably cut short when logging started "
                                   "mid-line; skipped",
                                   text::quote_line(line), bad));
    else if (ends_file)
      reporter_.report(Severity::note, n,
                       fmt::format("last line {} is cut short (the file ends mid-line: {}); skipped",
                                   text::quote_line(line), bad));
    else
      reporter_.warn(n, fmt::format("{}: {}; skipped", text::quote_line(line), bad));
  }

  void on_banner(const SpindownBanner& b, std::int64_t n) {
    ++banners_;
    if (!banner_seen_)
      rec_.note(n, "banner: " + describe(b));
    else if (!same_banner(banner_, b))
      reporter_.report(Severity::note, n, "new banner: " + describe(b));
    banner_ = b;
    banner_seen_ = banner_since_sample_ = true;
  }

  void on_sample(const SpindownLine& parsed, std::string_view line, std::int64_t n) {
    // The firmware numbers samples from 0 at boot: after a banner, a sequence number that does
    // not go on from the last one is the board's reset, even if micros() went forward.
    const std::uint32_t ahead = parsed.seq - (last_seq_ + 1);  // modulo 2^32
    const bool seq_back = have_seq_ && parsed.seq != last_seq_ && ahead >= 0x80000000u;
    const DeviceClock::Reading r = read_clock(parsed, n, seq_back);
    if (have_seq_ && parsed.seq != last_seq_ + 1) check_sequence(parsed, n, seq_back, ahead);
    have_seq_ = gaps_are_losses_ = true;
    banner_since_sample_ = false;
    garbled_since_sample_ = 0;
    last_seq_ = parsed.seq;
    last_time_us_ = parsed.time_us;
    last_sample_line_ = n;
    if (!banner_seen_ && before_banner_++ == 0) first_before_banner_ = n;
    raw_.add(n, line.data(), static_cast<double>(r.time_us), banner_.volts(parsed.adc), raw_.size() == 0);
  }

  // micros() unwrapped; a board reset ends the clock epoch (a new timeline, no run spans it).
  DeviceClock::Reading read_clock(const SpindownLine& parsed, std::int64_t n, bool seq_back) {
    if (banner_since_sample_ && seq_back) clock_.mark_reset();
    const DeviceClock::Reading r = clock_.update(parsed.time_us);
    if (r.reset) {
      end_epoch();
      reporter_.report(
          Severity::note, n,
          seq_back && banner_since_sample_
              ? fmt::format("board reset: a banner, then the sequence starts again at {} (line {} had {}); a new "
                            "timeline starts here and no run spans it",
                            parsed.seq, last_sample_line_, last_seq_)
              : fmt::format("device clock restarted (board reset?): micros() goes back from {} µs (line {}) to {} "
                            "µs; a new timeline starts here and no run spans it",
                            last_time_us_, last_sample_line_, parsed.time_us));
      ++timeline_.restarts;
      have_seq_ = false;
    } else if (r.wrapped) {
      ++timeline_.wraps;
      reporter_.report(Severity::note, n,
                       fmt::format("device clock wrapped from {} µs to {} µs (micros() overflow at 2^32 µs); "
                                   "unwrapped",
                                   last_time_us_, parsed.time_us));
    }
    return r;
  }

  // A sequence number that does not follow the last: a repeat, a step back, or samples lost.
  void check_sequence(const SpindownLine& parsed, std::int64_t n, bool seq_back, std::uint32_t ahead) {
    if (parsed.seq == last_seq_) {
      // The same line twice has the same time too: the timeline says so and skips it.
      if (parsed.time_us != last_time_us_)
        reporter_.warn(n, fmt::format("sequence number {} repeats line {} with another time ({} µs, then {} µs)",
                                      parsed.seq, last_sample_line_, last_time_us_, parsed.time_us));
    } else if (seq_back) {
      reporter_.warn(n, fmt::format("sequence number goes back from {} (line {}) to {} (line {}) while the clock "
                                    "runs on",
                                    last_seq_, last_sample_line_, parsed.seq, n));
    } else if (gaps_are_losses_) {
      lost_ += ahead;
      reporter_.warn(n, fmt::format("sequence number jumps from {} (line {}) to {} (line {}): {} sample{} lost{}",
                                    last_seq_, last_sample_line_, parsed.seq, n, ahead, ahead == 1 ? "" : "s",
                                    garbled_since_sample_ == 0 ? std::string()
                                    : garbled_since_sample_ == 1
                                        ? fmt::format(" (line {} between was garbled)", first_garbled_since_)
                                        : fmt::format(" ({} garbled lines between, from line {})",
                                                      garbled_since_sample_, first_garbled_since_)));
    }
  }

  // The samples of the current clock epoch, turned into the Recording's timeline by the Arduino
  // reader's code when the epoch ends (their times already unwrapped: no wrap, no restart there).
  void end_epoch() {
    if (raw_.size() == 0) return;
    if (!rec_.empty()) rec_.clock_restarts.push_back(rec_.size());
    const text::TimelineCounts c = text::build_timeline(raw_, rules_, rec_, reporter_);
    timeline_.cut_first += c.cut_first;
    timeline_.backwards += c.backwards;
    timeline_.ahead += c.ahead;
    timeline_.duplicates += c.duplicates;
    timeline_.gaps += c.gaps;
    raw_ = text::RawSamples(text_);
  }

  void finish(std::int64_t lines) {
    const SpindownBanner defaults{};
    if (before_banner_ > 0 && !rec_.empty())
      rec_.warn(first_before_banner_,
                fmt::format("{} sample{} from this line on came before any banner: converted with the protocol's "
                            "defaults ({}-bit ADC at {:.3f} V full scale); the firmware prints its banner when it "
                            "starts, so the capture began after that",
                            before_banner_, before_banner_ == 1 ? "" : "s", defaults.adc_bits, defaults.adc_ref_v));
    reporter_.finish();
    text::sort_by_line(rec_);
    rec_.lines_read = static_cast<std::size_t>(lines);
    rec_.lines_skipped = rec_.lines_read - rec_.size();
    if (rec_.empty()) {
      if (first_bad_line_ > 0)
        rec_.error(0, fmt::format("no samples: none of the {} lines is a spindown-v1 sample (line {}: {})", lines,
                                  first_bad_line_, first_bad_why_));
      else
        rec_.error(0, fmt::format("no samples: {} lines, {} blank, {} header lines, {} banners, {} firmware notes",
                                  lines, blank_, headers_, banners_, notes_));
      return;
    }
    rec_.note(0, text::summary_with_counts(fmt::format("{} spindown-v1 samples from {} lines", rec_.size(), lines),
                                           {{headers_, "PuTTY header"},
                                            {banners_, "banner"},
                                            {notes_, "firmware note"},
                                            {blank_, "blank"},
                                            {cut_, "cut short"},
                                            {garbled_, "garbled"},
                                            {static_cast<std::size_t>(lost_), "lost in sequence gaps"},
                                            {before_banner_, "before any banner"}},
                                           timeline_));
  }

  std::string_view text_;
  const SpindownTextOptions& options_;
  Recording rec_;
  text::LineReporter reporter_;
  DeviceClock clock_{1};  // micros() as the bridge reads it: one tick a µs, wrapping at 2^32
  SpindownBanner banner_;  // the conversion in force (the protocol's defaults until a banner)
  bool banner_seen_ = false;
  bool banner_since_sample_ = false;  // a banner came after the last sample
  text::RawSamples raw_;
  text::TimelineRules rules_;
  text::TimelineCounts timeline_;
  std::size_t blank_ = 0, headers_ = 0, garbled_ = 0, cut_ = 0, banners_ = 0, notes_ = 0, before_banner_ = 0;
  std::int64_t lost_ = 0, first_before_banner_ = 0, first_bad_line_ = 0;
  std::string first_bad_why_;
  bool first_content_ = true;    // the next non-blank line is the first of a logging session
  bool have_seq_ = false;        // last_seq_ is the previous sample's, in this clock epoch
  bool gaps_are_losses_ = false;  // no logging session began since that sample
  std::uint32_t last_seq_ = 0, last_time_us_ = 0;
  std::int64_t last_sample_line_ = 0;
  std::size_t garbled_since_sample_ = 0;  // garbled lines since the last sample, from this line
  std::int64_t first_garbled_since_ = 0;
};

}  // namespace

Recording read_spindown_text(std::string_view text, std::string source, const SpindownTextOptions& options,
                             std::int64_t* samples_lost) {
  if (samples_lost) *samples_lost = 0;
  return SpindownReader(text, std::move(source), options).read(samples_lost);
}

Recording read_spindown_text_file(const std::string& path, const SpindownTextOptions& options) {
  return text::read_text_file(path, options, [](std::string_view bytes, const std::string& source, const auto& o) {
    return read_spindown_text(bytes, source, o);
  });
}

}  // namespace spindown
