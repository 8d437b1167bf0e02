#include "spindown/text_support.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>

namespace spindown::text {

namespace {

// A byte that is a control character in text: below 0x20 except tab, LF and CR, or DEL.
constexpr bool is_control_byte(unsigned char c) { return (c < 0x20 || c == 0x7F) && c != '\t' && c != '\n' && c != '\r'; }

// Control bytes in p[0, n), 16 at a time with GCC's vector extension (SSE2 compares, ~1
// instruction a byte; a table lookup per byte was 6 and the largest cost of reading a small file).
std::size_t count_control_bytes(const unsigned char* p, std::size_t n) {
  using Bytes = unsigned char __attribute__((vector_size(16)));
  std::size_t control = 0, i = 0;
  while (n - i >= sizeof(Bytes)) {
    // Per-lane counts in bytes: flush before any lane can pass 255.
    Bytes lanes{};
    for (int block = 0; block < 255 && n - i >= sizeof(Bytes); ++block, i += sizeof(Bytes)) {
      Bytes b;
      std::memcpy(&b, p + i, sizeof b);
      const auto hit = ((b < 0x20) | (b == 0x7F)) & (b != '\t') & (b != '\n') & (b != '\r');
      lanes -= reinterpret_cast<Bytes>(hit);  // a hit lane is -1 (all bits set)
    }
    for (std::size_t k = 0; k < sizeof(Bytes); ++k) control += lanes[k];
  }
  for (; i < n; ++i) control += is_control_byte(p[i]);
  return control;
}

// looks_binary looks at this many bytes from the start.
constexpr std::size_t binary_window = 8 * 1024;

}  // namespace

BinaryCheck::BinaryCheck(std::string_view text)
    : begin_(text.data()), looked_at_(std::min(text.size(), binary_window)) {}

void BinaryCheck::count(const char* from, const char* to) {
  const char* const window_end = begin_ + looked_at_;
  if (to > window_end) to = window_end;
  if (from >= to) return;
  control_bytes_ += count_control_bytes(reinterpret_cast<const unsigned char*>(from), static_cast<std::size_t>(to - from));
}

bool looks_binary(std::string_view bytes, std::size_t* control_bytes, std::size_t* looked_at) {
  const std::size_t n = std::min<std::size_t>(bytes.size(), binary_window);
  const std::size_t control = count_control_bytes(reinterpret_cast<const unsigned char*>(bytes.data()), n);
  if (control_bytes) *control_bytes = control;
  if (looked_at) *looked_at = n;
  return n > 0 && control * 10 > n;
}

std::string quote_line(std::string_view line) {
  constexpr std::size_t max_shown = 40;  // characters
  std::string out = "\"";
  std::size_t i = 0;
  for (std::size_t shown = 0; i < line.size() && shown < max_shown; ++shown) {
    const auto c = static_cast<unsigned char>(line[i]);
    const std::size_t len = utf8_sequence_length(line, i);
    if (c == '\t') out += "\\t";
    else if (c == '\r') out += "\\r";
    else if (c == '\\') out += "\\\\";
    else if (c == '"') out += "\\\"";
    else if (c < 0x20 || c == 0x7F || len == 0) out += fmt::format("\\x{:02x}", c);  // control or not UTF-8
    else out.append(line.substr(i, len));
    i += len == 0 ? 1 : len;
  }
  out += '"';
  if (i < line.size()) out += fmt::format("… ({} bytes)", line.size());
  return out;
}

void LineReporter::report(Diagnostic::Severity severity, std::int64_t line, std::string message) {
  ++count_;
  if (count_ <= max_) {
    rec_.diagnostics.push_back({severity, rec_.source, line, std::move(message)});
    return;
  }
  // Reports do not come in line order (the timeline's follow the parser's), so the range is the
  // lowest and highest line, and each severity is counted.
  if (first_unlisted_ == 0 || line < first_unlisted_) first_unlisted_ = line;
  last_unlisted_ = std::max(last_unlisted_, line);
  ++unlisted_[static_cast<int>(severity)];
}

void LineReporter::finish() {
  if (count_ <= max_) return;
  std::string kinds;
  constexpr std::pair<Diagnostic::Severity, const char*> names[] = {
      {Diagnostic::Severity::error, "error"}, {Diagnostic::Severity::warning, "warning"},
      {Diagnostic::Severity::note, "note"}};
  for (const auto& [severity, name] : names)
    if (const std::size_t n = unlisted_[static_cast<int>(severity)])
      kinds += fmt::format("{}{} {}{}", kinds.empty() ? "" : ", ", n, name, n == 1 ? "" : "s");
  rec_.warn(0, fmt::format("{} more problem lines not listed one by one ({}; between lines {} and {}); {} in all",
                           count_ - max_, kinds, first_unlisted_, last_unlisted_, count_));
}

void sort_by_line(Recording& rec) {
  auto key = [](const Diagnostic& d) { return d.line > 0 ? d.line : INT64_MAX; };
  std::stable_sort(rec.diagnostics.begin(), rec.diagnostics.end(),
                   [&](const Diagnostic& a, const Diagnostic& b) { return key(a) < key(b); });
}

std::string putty_header_note(std::string_view line) {
  constexpr std::string_view tag = "PuTTY log ";
  const std::size_t at = line.find(tag);
  if (at != std::string_view::npos) {
    std::string_view when = line.substr(at + tag.size());
    when = when.substr(0, std::min(when.find(" ="), std::size_t{40}));
    return fmt::format("PuTTY log header skipped (log started {})", escape_invalid_utf8(when));
  }
  return fmt::format("PuTTY log header skipped: {}", quote_line(line));
}

const RawSamples::Block& RawSamples::block_of(std::size_t i) const {
  const auto after = std::upper_bound(blocks_.begin(), blocks_.end(), i,
                                      [](std::size_t k, const Block& b) { return k < b.first; });
  return *(after - 1);
}

std::int64_t RawSamples::line(std::size_t i) const {
  const Block& b = block_of(i);
  return b.first_line + static_cast<std::int64_t>(i - b.first);
}

std::string_view RawSamples::text(std::size_t i) const {
  const Block& b = block_of(i);
  LineCursor lines(std::string_view(b.start, static_cast<std::size_t>(text_end_ - b.start)));
  std::string_view line;
  for (std::size_t k = b.first; k <= i; ++k) line = lines.next_line();
  return line;
}

namespace {

// Median of the positive steps between consecutive times in t[from, from + count].
double median_step(const std::vector<double>& t, std::size_t from, std::size_t count) {
  double steps[64];
  std::size_t n = 0;
  for (std::size_t i = from + 1; i < t.size() && i <= from + count && n < 64; ++i) {
    const double d = t[i] - t[i - 1];
    if (d > 0) steps[n++] = d;
  }
  if (n == 0) return 0;
  std::nth_element(steps, steps + n / 2, steps + n);
  return steps[n / 2];
}

}  // namespace

TimelineCounts build_timeline(RawSamples& raw, const TimelineRules& rules, Recording& rec, LineReporter& reporter) {
  using Severity = Diagnostic::Severity;
  TimelineCounts counts;
  const double period = median_step(raw.t, 0, 64);
  // A step larger than this is a gap in the data, or a garbled time if the next sample
  // continues from the previous one.
  const double jump = period > 0 ? std::max(20 * period, 0.5 * rules.units_per_s) : rules.units_per_s;
  const auto u = rules.unit;
  const double units_per_s = rules.units_per_s;

  // Samples kept are written back at kept (never past the one being looked at, so the samples
  // ahead that the checks read are untouched), then handed to rec. The arrays do not change size
  // in the loop: plain pointers, which stay in registers.
  const std::size_t n = raw.size();
  const std::size_t rec_base = rec.size();
  const double* const t = raw.t.data();
  const double* const values = raw.value.data();
  double* const t_out = raw.t.data();
  double* const v_out = raw.value.data();
  std::size_t kept = 0;
  const auto& blocks = raw.blocks();
  std::size_t next_block = 0;  // blocks[next_block] is the next to start, at sample next_first
  std::size_t next_first = blocks.empty() ? n : blocks.front().first;

  bool have_prev = false;
  double offset = 0;   // wraps so far in this clock epoch, in file units
  double prev_u = 0;   // unwrapped time of the last accepted sample
  std::size_t prev_i = 0;  // its index (its line, for messages)
  double prev_value = 0;

  for (std::size_t i = 0; i < n; ++i) {
    // The usual sample, up to the next block's first: a step forward no longer than a jump, kept
    // with nothing to check or report. A tight loop; the first sample it does not take (a
    // block's first, or a step that is not the usual one) goes on to the full checks below.
    if (have_prev && i < next_first) {
      double last_u = prev_u;
      std::size_t j = i;
      // Two at a time first (SSE2 pairs, the same sums and quotients lane by lane): a pair with
      // a step that is not the usual one is left to the loop after, one sample at a time.
      using Pair = double __attribute__((vector_size(16)));
      for (; j + 1 < next_first; j += 2) {
        Pair cur;
        std::memcpy(&cur, t + j, sizeof cur);
        cur += offset;
        const Pair before = {last_u, cur[0]};
        const Pair d = cur - before;
        const auto usual = (d > 0) & (d <= jump);
        if (!(usual[0] && usual[1])) break;
        const Pair seconds = cur / units_per_s;
        std::memcpy(t_out + kept, &seconds, sizeof seconds);
        std::memmove(v_out + kept, values + j, 2 * sizeof(double));
        kept += 2;
        last_u = cur[1];
      }
      for (; j < next_first; ++j) {
        const double cur_u = t[j] + offset;
        const double d = cur_u - last_u;
        if (!(d > 0 && d <= jump)) break;
        t_out[kept] = cur_u / units_per_s;
        v_out[kept] = values[j];
        ++kept;
        last_u = cur_u;
      }
      if (j > i) {
        prev_u = last_u;
        prev_i = j - 1;
        prev_value = v_out[kept - 1];
        i = j;
        if (i == n) break;
      }
    }
    const double s_t = t[i];
    const double s_value = values[i];
    const bool has_next = i + 1 < n;

    if (i == next_first) {  // a block's first sample: a new session's may have been cut short
      const bool session_start = blocks[next_block].session_start;
      ++next_block;
      next_first = next_block < blocks.size() ? blocks[next_block].first : n;
      if (session_start && rules.drop_cut_first && i + 3 < n) {
        const double local = median_step(raw.t, i + 1, 9);
        const double d = t[i + 1] - s_t;
        if (local > 0 && (d <= 0 || d > std::max(4 * local, local + 0.1 * rules.units_per_s))) {
          ++counts.cut_first;
          reporter.report(Severity::note, raw.line(i),
                          fmt::format("first sample {} looks cut short (logging started mid-line): its "
                                      "time {} {} does not fit the next samples ({} {}, then every ~{} {}); "
                                      "dropped",
                                      quote_line(raw.text(i)), s_t, u, t[i + 1], u, local, u));
          continue;
        }
      }
    }

    double cur_u = s_t + offset;
    const double d = cur_u - prev_u;
    if (have_prev && !(d > 0 && d <= jump)) {  // the usual step forward has nothing to report
      const std::int64_t line = raw.line(i);
      const std::int64_t prev_line = raw.line(prev_i);
      const double next_t = has_next ? t[i + 1] : 0;
      const double next_u = has_next ? next_t + offset : 0;
      if (d == 0) {
        ++counts.duplicates;
        reporter.warn(line, fmt::format("{}: time {} {} repeats line {}{}; skipped", quote_line(raw.text(i)), s_t,
                                        u, prev_line, s_value == prev_value ? " (duplicate line)" : ""));
        continue;
      }
      if (d > 0) {
        if (d > jump && has_next && next_u > prev_u && next_u < cur_u && next_u - prev_u <= jump) {
          ++counts.ahead;
          reporter.warn(line, fmt::format("{}: time {} {} jumps ahead of its neighbours (line {} has {} {}, "
                                          "the next sample {} {}); skipped",
                                          quote_line(raw.text(i)), s_t, u, prev_line, prev_u - offset, u, next_t, u));
          continue;
        }
        if (d > jump) {
          ++counts.gaps;
          reporter.report(Severity::note, line,
                          fmt::format("no samples for {:.3g} s of device time (lines {} to {})",
                                      d / rules.units_per_s, prev_line, line));
        }
      } else {  // time went back
        const double prev_raw = prev_u - offset;
        const double window = 600 * rules.units_per_s;
        if (rules.wrap > 0 && prev_raw > rules.wrap - window && s_t < window && d + rules.wrap > 0 &&
            d + rules.wrap <= std::max(jump, window)) {
          ++counts.wraps;
          offset += rules.wrap;
          cur_u += rules.wrap;
          reporter.report(Severity::note, line,
                          fmt::format("device clock wrapped from {} {} to {} {} (counter overflow at {} {}); "
                                      "unwrapped",
                                      prev_raw, u, s_t, u, rules.wrap, u));
        } else if (has_next && next_u > prev_u && next_u - prev_u <= jump) {
          ++counts.backwards;
          reporter.warn(line, fmt::format("{}: time goes back from {} {} (line {}) to {} {} and the next "
                                          "sample continues from {} {}; skipped",
                                          quote_line(raw.text(i)), prev_raw, u, prev_line, s_t, u, next_t, u));
          continue;
        } else if (-d >= rules.reset_min_back && has_next && next_u >= cur_u && next_u - cur_u <= jump) {
          ++counts.restarts;
          offset = 0;
          cur_u = s_t;
          rec.clock_restarts.push_back(rec_base + kept);
          reporter.report(Severity::note, line,
                          fmt::format("device clock restarted (Arduino reset?): time goes back from {} {} "
                                      "(line {}) to {} {}; a new timeline starts here and no run spans it",
                                      prev_raw, u, prev_line, s_t, u));
        } else {
          ++counts.backwards;
          reporter.warn(line, fmt::format("{}: time goes back from {} {} (line {}) to {} {}; skipped",
                                          quote_line(raw.text(i)), prev_raw, u, prev_line, s_t, u));
          continue;
        }
      }
    }
    t_out[kept] = cur_u / units_per_s;
    v_out[kept] = s_value;
    ++kept;
    have_prev = true;
    prev_u = cur_u;
    prev_i = i;
    prev_value = s_value;
  }

  raw.t.resize(kept);
  raw.value.resize(kept);
  if (rec_base == 0) {
    rec.t_s = std::move(raw.t);
    rec.value = std::move(raw.value);
  } else {
    rec.t_s.insert(rec.t_s.end(), raw.t.begin(), raw.t.end());
    rec.value.insert(rec.value.end(), raw.value.begin(), raw.value.end());
  }
  return counts;
}

std::string summary_with_counts(std::string head, std::initializer_list<Count> counts, const TimelineCounts& timeline) {
  auto add = [&](std::size_t n, std::string_view what) {
    if (n > 0) head += fmt::format(", {} {}", n, what);
  };
  for (const Count& c : counts) add(c.n, c.what);
  add(timeline.cut_first, "cut first line");
  add(timeline.backwards, "time going back");
  add(timeline.ahead, "time jumping ahead");
  add(timeline.duplicates, "repeated time");
  add(timeline.restarts, "clock restart");
  add(timeline.wraps, "clock wrap");
  return head;
}

std::string binary_data_error(std::string_view what, std::size_t control_bytes, std::size_t looked_at) {
  return fmt::format("no samples: binary data, not {} ({} of the first {} bytes are control characters or NUL)", what,
                     control_bytes, looked_at);
}

}  // namespace spindown::text
