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

namespace {

using Severity = Diagnostic::Severity;

// build_timeline's pass over the samples. Samples kept are written back at kept (never past the
// one being looked at, so the samples ahead that the checks read are untouched), then handed to
// rec. The arrays do not change size in the pass.
class TimelineBuilder {
 public:
  TimelineBuilder(RawSamples& raw, const TimelineRules& rules, Recording& rec, LineReporter& reporter)
      : raw_(raw), rules_(rules), rec_(rec), reporter_(reporter), u_(rules.unit), n_(raw.size()),
        rec_base_(rec.size()), t_(raw.t.data()), values_(raw.value.data()), t_out_(raw.t.data()),
        v_out_(raw.value.data()), next_first_(raw.blocks().empty() ? n_ : raw.blocks().front().first) {
    const double period = median_step(raw.t, 0, 64);
    // A step larger than this is a gap in the data, or a garbled time if the next sample
    // continues from the previous one.
    jump_ = period > 0 ? std::max(20 * period, 0.5 * rules.units_per_s) : rules.units_per_s;
  }

  TimelineCounts run() && {
    for (std::size_t i = 0; i < n_; ++i) {
      if (have_prev_ && i < next_first_) {
        i = take_usual_steps(i);
        if (i == n_) break;
      }
      if (i == next_first_ && start_block(i)) continue;  // a cut-short first sample, dropped
      double cur_u = t_[i] + offset_;
      const double d = cur_u - prev_u_;
      // The usual step forward has nothing to report; anything else may be skipped.
      if (have_prev_ && !(d > 0 && d <= jump_) && !unusual_step(i, d, cur_u)) continue;
      keep(i, cur_u);
    }
    hand_over();
    return counts_;
  }

 private:
  void keep(std::size_t i, double cur_u) {
    t_out_[kept_] = cur_u / rules_.units_per_s;
    v_out_[kept_] = values_[i];
    ++kept_;
    have_prev_ = true;
    prev_u_ = cur_u;
    prev_i_ = i;
    prev_value_ = values_[i];
  }

  // The usual samples from i, up to the next block's first: each a step forward no longer than a
  // jump, kept with nothing to check or report. A tight loop over locals, which stay in registers;
  // returns the first sample it did not take (a block's first, or a step that is not the usual
  // one), which goes on to the full checks.
  std::size_t take_usual_steps(std::size_t i) {
    const double* const t = t_;
    const double offset = offset_, jump = jump_, units_per_s = rules_.units_per_s;
    double* const t_out = t_out_;
    double* const v_out = v_out_;
    std::size_t kept = kept_;
    double last_u = prev_u_;
    std::size_t j = i;
    // Two at a time first (SSE2 pairs, the same sums and quotients lane by lane): a pair with a
    // step that is not the usual one is left to the loop after, one sample at a time.
    using Pair = double __attribute__((vector_size(16)));
    for (; j + 1 < next_first_; j += 2) {
      Pair cur;
      std::memcpy(&cur, t + j, sizeof cur);
      cur += offset;
      const Pair before = {last_u, cur[0]};
      const Pair d = cur - before;
      const auto usual = (d > 0) & (d <= jump);
      if (!(usual[0] && usual[1])) break;
      const Pair seconds = cur / units_per_s;
      std::memcpy(t_out + kept, &seconds, sizeof seconds);
      std::memmove(v_out + kept, values_ + j, 2 * sizeof(double));
      kept += 2;
      last_u = cur[1];
    }
    for (; j < next_first_; ++j) {
      const double cur_u = t[j] + offset;
      const double d = cur_u - last_u;
      if (!(d > 0 && d <= jump)) break;
      t_out[kept] = cur_u / units_per_s;
      v_out[kept] = values_[j];
      ++kept;
      last_u = cur_u;
    }
    if (j > i) {
      kept_ = kept;
      prev_u_ = last_u;
      prev_i_ = j - 1;
      prev_value_ = v_out[kept - 1];
    }
    return j;
  }

  // A block's first sample: a new session's may have been cut short (logging started mid-line).
  // True when it is dropped.
  bool start_block(std::size_t i) {
    const auto& blocks = raw_.blocks();
    const bool session_start = blocks[next_block_].session_start;
    ++next_block_;
    next_first_ = next_block_ < blocks.size() ? blocks[next_block_].first : n_;
    if (!session_start || !rules_.drop_cut_first || i + 3 >= n_) return false;
    const double local = median_step(raw_.t, i + 1, 9);
    const double d = t_[i + 1] - t_[i];
    if (!(local > 0 && (d <= 0 || d > std::max(4 * local, local + 0.1 * rules_.units_per_s)))) return false;
    ++counts_.cut_first;
    reporter_.report(Severity::note, raw_.line(i),
                     fmt::format("first sample {} looks cut short (logging started mid-line): its "
                                 "time {} {} does not fit the next samples ({} {}, then every ~{} {}); "
                                 "dropped",
                                 quote_line(raw_.text(i)), t_[i], u_, t_[i + 1], u_, local, u_));
    return true;
  }

  // A step that is not the usual one (d from the last kept sample): a repeat, a time ahead of its
  // neighbours, a gap, a wrap, a garbled time or a restart. False when the sample is skipped;
  // cur_u is unwrapped or restarted in place.
  bool unusual_step(std::size_t i, double d, double& cur_u) {
    const double s_t = t_[i];
    const std::int64_t line = raw_.line(i);
    const std::int64_t prev_line = raw_.line(prev_i_);
    const bool has_next = i + 1 < n_;
    const double next_t = has_next ? t_[i + 1] : 0;
    const double next_u = has_next ? next_t + offset_ : 0;
    if (d == 0) {
      ++counts_.duplicates;
      reporter_.warn(line, fmt::format("{}: time {} {} repeats line {}{}; skipped", quote_line(raw_.text(i)), s_t, u_,
                                       prev_line, values_[i] == prev_value_ ? " (duplicate line)" : ""));
      return false;
    }
    if (d > 0) {
      if (d > jump_ && has_next && next_u > prev_u_ && next_u < cur_u && next_u - prev_u_ <= jump_) {
        ++counts_.ahead;
        reporter_.warn(line, fmt::format("{}: time {} {} jumps ahead of its neighbours (line {} has {} {}, "
                                         "the next sample {} {}); skipped",
                                         quote_line(raw_.text(i)), s_t, u_, prev_line, prev_u_ - offset_, u_, next_t,
                                         u_));
        return false;
      }
      ++counts_.gaps;
      reporter_.report(Severity::note, line,
                       fmt::format("no samples for {:.3g} s of device time (lines {} to {})", d / rules_.units_per_s,
                                   prev_line, line));
      return true;
    }
    return went_back(i, d, cur_u, has_next, next_t, next_u);
  }

  // Time went back: the counter wrapped, a garbled time between good ones, or the clock restarted.
  bool went_back(std::size_t i, double d, double& cur_u, bool has_next, double next_t, double next_u) {
    const double s_t = t_[i];
    const std::int64_t line = raw_.line(i);
    const std::int64_t prev_line = raw_.line(prev_i_);
    const double prev_raw = prev_u_ - offset_;
    const double window = 600 * rules_.units_per_s;
    const double wrap = rules_.wrap;
    if (wrap > 0 && prev_raw > wrap - window && s_t < window && d + wrap > 0 && d + wrap <= std::max(jump_, window)) {
      ++counts_.wraps;
      offset_ += wrap;
      cur_u += wrap;
      reporter_.report(Severity::note, line,
                       fmt::format("device clock wrapped from {} {} to {} {} (counter overflow at {} {}); unwrapped",
                                   prev_raw, u_, s_t, u_, wrap, u_));
      return true;
    }
    if (has_next && next_u > prev_u_ && next_u - prev_u_ <= jump_) {
      ++counts_.backwards;
      reporter_.warn(line, fmt::format("{}: time goes back from {} {} (line {}) to {} {} and the next "
                                       "sample continues from {} {}; skipped",
                                       quote_line(raw_.text(i)), prev_raw, u_, prev_line, s_t, u_, next_t, u_));
      return false;
    }
    if (-d >= rules_.reset_min_back && has_next && next_u >= cur_u && next_u - cur_u <= jump_) {
      ++counts_.restarts;
      offset_ = 0;
      cur_u = s_t;
      rec_.clock_restarts.push_back(rec_base_ + kept_);
      reporter_.report(Severity::note, line,
                       fmt::format("device clock restarted (Arduino reset?): time goes back from {} {} "
                                   "(line {}) to {} {}; a new timeline starts here and no run spans it",
                                   prev_raw, u_, prev_line, s_t, u_));
      return true;
    }
    ++counts_.backwards;
    reporter_.warn(line, fmt::format("{}: time goes back from {} {} (line {}) to {} {}; skipped",
                                     quote_line(raw_.text(i)), prev_raw, u_, prev_line, s_t, u_));
    return false;
  }

  void hand_over() {
    raw_.t.resize(kept_);
    raw_.value.resize(kept_);
    if (rec_base_ == 0) {
      rec_.t_s = std::move(raw_.t);
      rec_.value = std::move(raw_.value);
    } else {
      rec_.t_s.insert(rec_.t_s.end(), raw_.t.begin(), raw_.t.end());
      rec_.value.insert(rec_.value.end(), raw_.value.begin(), raw_.value.end());
    }
  }

  RawSamples& raw_;
  const TimelineRules& rules_;
  Recording& rec_;
  LineReporter& reporter_;
  const std::string_view u_;
  const std::size_t n_;
  const std::size_t rec_base_;
  const double* const t_;
  const double* const values_;
  double* const t_out_;
  double* const v_out_;
  double jump_ = 0;
  TimelineCounts counts_;
  std::size_t kept_ = 0;
  std::size_t next_block_ = 0;  // blocks[next_block_] is the next to start, at sample next_first_
  std::size_t next_first_;
  bool have_prev_ = false;
  double offset_ = 0;       // wraps so far in this clock epoch, in file units
  double prev_u_ = 0;       // unwrapped time of the last accepted sample
  std::size_t prev_i_ = 0;  // its index (its line, for messages)
  double prev_value_ = 0;
};

}  // namespace

TimelineCounts build_timeline(RawSamples& raw, const TimelineRules& rules, Recording& rec, LineReporter& reporter) {
  return TimelineBuilder(raw, rules, rec, reporter).run();
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

namespace spindown::text {

std::optional<std::string> written_name(std::string_view line) {
  const auto trim = [](std::string_view s, std::string_view chars) {
    while (!s.empty() && chars.find(s.front()) != std::string_view::npos) s.remove_prefix(1);
    while (!s.empty() && chars.find(s.back()) != std::string_view::npos) s.remove_suffix(1);
    return s;
  };
  // Separators after it (a spreadsheet's empty cells), then a comment's or a heading's marks.
  std::string_view s = trim(line, " \t\r;,");
  s = trim(s, " #-=*/>:~");
  if (s.empty() || s.size() > 60) return std::nullopt;
  // A line with a field after a delimiter, brackets or a unit is a header or a table's row.
  if (s.find_first_of("\t;[]()<>{}|\"=") != std::string_view::npos) return std::nullopt;
  // A letter's length in bytes at i (0: none): ASCII letters, and in UTF-8 the Latin, Greek and
  // Cyrillic letters and combining accents (a name from a Mac's folder is decomposed). Bytes that
  // are no such letter (a garbled line's) make no name.
  const auto letter = [&s](std::size_t i) -> std::size_t {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    if ((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z')) return 1;
    if (c < 0xC2 || c > 0xE1 || i + 1 >= s.size()) return 0;
    const unsigned char c1 = static_cast<unsigned char>(s[i + 1]);
    if ((c1 & 0xC0) != 0x80) return 0;
    if (c < 0xE0) {
      const unsigned cp = ((c & 0x1Fu) << 6) | (c1 & 0x3Fu);
      const bool latin = cp >= 0xC0 && cp <= 0x24F && cp != 0xD7 && cp != 0xF7;
      return latin || (cp >= 0x300 && cp <= 0x36F) || (cp >= 0x370 && cp <= 0x4FF) ? 2 : 0;
    }
    if (i + 2 >= s.size() || (static_cast<unsigned char>(s[i + 2]) & 0xC0) != 0x80) return 0;
    const unsigned cp = ((c & 0x0Fu) << 12) | ((c1 & 0x3Fu) << 6) | (static_cast<unsigned char>(s[i + 2]) & 0x3Fu);
    return cp >= 0x1E00 && cp <= 0x1EFF ? 3 : 0;  // Latin Extended Additional (Vietnamese, Welsh)
  };
  const auto upper = [](unsigned char c) { return (c >= 'A' && c <= 'Z') || c >= 0x80; };
  std::string name;
  std::size_t words = 0, at = 0;
  while (at < s.size() && words < 3) {
    std::size_t end = at;
    while (end < s.size()) {
      if (s[end] == '-' || s[end] == '\'') {
        ++end;
      } else if (const std::size_t n = letter(end)) {
        end += n;
      } else {
        break;
      }
    }
    const std::string_view w = s.substr(at, end - at);
    if (w.empty() || !upper(static_cast<unsigned char>(w.front()))) break;  // "run", "2nd", a number
    (name += name.empty() ? "" : " ") += w;
    ++words;
    at = end;
    if (at < s.size() && s[at] != ' ') break;  // ", 2nd try", ": run 1"
    while (at < s.size() && s[at] == ' ') ++at;
  }
  if (words == 0 || name.size() < 2) return std::nullopt;
  // The rest may say which run or try; never a number alone or a reading.
  if (at < s.size()) {
    const char c = s[at];
    if (c != ',' && c != ':' && c != '-' && !(c >= 'a' && c <= 'z')) return std::nullopt;
    for (std::size_t i = at; i < s.size(); ++i)  // and the rest is text, not bytes
      if (static_cast<unsigned char>(s[i]) >= 0x80 && letter(i) == 0 && (static_cast<unsigned char>(s[i]) & 0xC0) != 0x80)
        return std::nullopt;
  }
  // Words a device or a header prints, capitalised as names are.
  static constexpr std::string_view not_names[] = {
      "Time", "Zeit", "Voltage", "Volts", "Volt", "Spannung", "Millis", "Micros", "Speed", "Value", "Values",
      "Sample", "Samples", "Channel", "Data", "Ready", "Start", "Starting", "Started", "Stop", "Reset", "Done",
      "Begin", "End", "Motor", "Arduino", "Error", "Boot", "Hello", "Ok", "OK", "Go", "Run", "Test", "Comment",
      "Rpm", "RPM", "Counts", "Current", "Strom", "Drehzahl", "Messung", "Measurement", "LabVIEW", "Spin",
      "Power", "Coast", "Coasting", "Setup", "Loop", "Serial", "Waiting", "Connected", "Sketch", "Version"};
  const std::string_view first = std::string_view(name).substr(0, name.find(' '));
  for (const std::string_view n : not_names)
    if (first == n) return std::nullopt;
  return name;
}

}  // namespace spindown::text
