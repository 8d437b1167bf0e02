#include "spindown/arduino_text.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "spindown/lab_line.hpp"
#include "spindown/text_support.hpp"

namespace spindown {

bool ArduinoTextOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  if (max_line_reports == 0) return fail("max_line_reports must be at least 1");
  if (!std::isfinite(reset_min_back_s) || reset_min_back_s <= 0)
    return fail(fmt::format("reset_min_back_s {} is not a positive number of seconds", reset_min_back_s));
  return true;
}

namespace {

bool is_putty_header(std::string_view line) { return line.starts_with("=~=~=~"); }

// "millis\tvolts", "time volts": words only, as a sketch prints in setup().
bool is_column_header(std::string_view line) {
  bool letters = false;
  for (char c : line) {
    if (c >= '0' && c <= '9') return false;
    if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) letters = true;
  }
  return letters;
}

// The median step between the first few hundred consecutive times (0: too few).
double median_step(const std::vector<double>& t) {
  std::vector<double> steps;
  for (std::size_t i = 1; i < t.size() && steps.size() < 400; ++i)
    if (t[i] > t[i - 1]) steps.push_back(t[i] - t[i - 1]);
  if (steps.size() < 5) return 0;
  std::nth_element(steps.begin(), steps.begin() + std::ptrdiff_t(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

// Whether median_step(t) is within [4000, 200000] (µs from sample to sample), from counts alone:
// the median of m steps, steps[m / 2] sorted, is at least 4000 when no more than m / 2 are below,
// and at most 200000 when no more than m - m / 2 - 1 are above (no sort for every file).
bool micros_clock(const std::vector<double>& t) {
  std::size_t m = 0, below = 0, above = 0;
  for (std::size_t i = 1; i < t.size() && m < 400; ++i) {
    if (!(t[i] > t[i - 1])) continue;
    const double step = t[i] - t[i - 1];
    ++m;
    below += step < 4000;
    above += step > 200000;
  }
  return m >= 5 && below <= m / 2 && above + 1 + m / 2 <= m;
}

}  // namespace

Recording read_arduino_text(std::string_view text, std::string source, const ArduinoTextOptions& options) {
  Recording rec;
  rec.source = std::move(source);
  rec.quantity = Quantity::back_emf_volts;
  // Binary data is refused as soon as the first 8 KiB are read, with only this error.
  if (!text::readable_text(text, options, "Arduino text", rec, false)) return rec;
  text::BinaryCheck binary(text);
  bool binary_decided = false;
  auto refuse_binary = [&] {
    Recording junk;
    junk.source = std::move(rec.source);
    junk.quantity = rec.quantity;
    junk.error(0, text::binary_data_error("Arduino text", binary.control_bytes(), binary.looked_at()));
    return junk;
  };

  text::LineReporter reporter(rec, options.max_line_reports);
  text::RawSamples raw(text);
  // The sketch's lines are 10 to 14 bytes; a block's room beyond that needs no reallocation. Capped,
  // so that a large file refused as binary after its first 8 KiB has not reserved much for it.
  constexpr std::size_t reserve_text_bytes = 1 << 20;
  raw.reserve(std::min(text.size(), reserve_text_bytes) / 10 + text::RawSamples::block_lines);
  std::size_t blank = 0, headers = 0, garbled = 0, column_headers = 0;
  bool session_start = true;   // next sample is the first of a logging session
  bool first_content = true;   // next non-blank line is the first of a session
  std::int64_t first_bad_line = 0;
  std::string_view first_bad_why;

  text::LineCursor cursor(text);
  while (!cursor.at_end()) {
    if (!binary_decided && binary.decided(cursor.rest().data())) {
      if (binary.binary()) return refuse_binary();
      binary_decided = true;
    }
    // Lines as the sketch prints them take the fast path: a block of them at a time, parsed
    // where they lie, no line split first.
    const std::size_t first = raw.size();
    const PrintedLines printed = parse_printed_lines(cursor.rest(), text::RawSamples::block_lines, raw.t, raw.value);
    if (printed.lines > 0) {
      raw.added_lines(first, cursor.line_number() + 1, cursor.rest().data(), session_start);
      cursor.skip_lines(printed.bytes, printed.lines);
      session_start = first_content = false;
      continue;
    }
    // Anything else is split off and judged by parse_lab_line, which names what is wrong.
    const std::string_view line = cursor.next_line();
    binary.count(line.data(), cursor.rest().data());  // the fast path's bytes are never control bytes
    const std::int64_t n = cursor.line_number();
    if (is_putty_header(line)) {
      ++headers;
      rec.note(n, text::putty_header_note(line));
      session_start = first_content = true;
      continue;
    }
    const LabLine parsed = parse_lab_line(line);
    if (parsed.kind == LabLine::Kind::blank) {
      ++blank;
      continue;
    }
    if (parsed.kind == LabLine::Kind::garbled) {
      // A sketch that prints whose run it is as a third column (set from the serial monitor's
      // send box): millis<TAB>volts<TAB>Łukasz. The sample is read; a new name is kept with it.
      if (const std::size_t tab1 = line.find('\t'), tab2 = tab1 == std::string_view::npos ? tab1 : line.find('\t', tab1 + 1);
          tab2 != std::string_view::npos) {
        const LabLine head = parse_lab_line(line.substr(0, tab2));
        const std::string_view tail = line.substr(tab2 + 1);
        const auto name = text::written_name(tail);
        if (head.kind == LabLine::Kind::sample && name) {
          if (rec.names.empty() || rec.names.back().name != *name) {
            rec.names.push_back({raw.size(), *name, n});
            rec.note(n, fmt::format("{}: a name in a third column: the runs from here are {}'s", text::quote_line(line),
                                    *name));
          }
          raw.add(n, line.data(), static_cast<double>(head.millis), head.value, session_start);
          session_start = first_content = false;
          continue;
        }
      }
      if (auto name = text::written_name(line)) {
        rec.names.push_back({raw.size(), *name, n});
        rec.note(n, fmt::format("{}: a name written between the samples: the runs after it are {}'s",
                                text::quote_line(line), *name));
        first_content = false;
        continue;
      }
      if (first_content && is_column_header(line)) {
        ++column_headers;
        rec.note(n, fmt::format("column header {} skipped", text::quote_line(line)));
      } else {
        ++garbled;
        if (first_bad_line == 0) {
          first_bad_line = n;
          first_bad_why = parsed.why;
        }
        if (first_content)
          reporter.report(Diagnostic::Severity::note, n,
                          fmt::format("first line {} is not a sample ({}), probably cut short when logging "
                                      "started mid-line; skipped",
                                      text::quote_line(line), parsed.why));
        else
          reporter.warn(n, fmt::format("{}: {}; skipped", text::quote_line(line), parsed.why));
      }
      first_content = false;
      continue;
    }
    raw.add(n, line.data(), static_cast<double>(parsed.millis), parsed.value, session_start);
    session_start = first_content = false;
  }
  if (!binary_decided && binary.binary()) return refuse_binary();  // all of it read: decided
  const std::int64_t lines = cursor.line_number();

  // A sketch that prints micros() instead of millis(): its loop of delay(20) steps the clock by
  // ~20,000. Steps of 4 to 200 "seconds" read as millis would leave no coast a second sample;
  // as µs they are the lab's 4–200 ms. (Both are unsigned 32-bit counters.)
  const double ticks_per_s = micros_clock(raw.t) ? 1e6 : 1000;
  text::TimelineRules rules;
  rules.units_per_s = ticks_per_s;
  rules.unit = ticks_per_s == 1000 ? "ms" : "us";
  rules.wrap = 4294967296.0;
  rules.reset_min_back = options.reset_min_back_s * ticks_per_s;
  rules.drop_cut_first = options.drop_cut_first_line;
  const text::TimelineCounts timeline = text::build_timeline(raw, rules, rec, reporter);
  reporter.finish();
  text::sort_by_line(rec);

  rec.lines_read = static_cast<std::size_t>(lines);
  rec.lines_skipped = rec.lines_read - rec.size();
  if (rec.empty()) {
    if (first_bad_line > 0)
      rec.error(0, fmt::format("no samples: none of the {} lines is a millis<TAB>volts sample (line {}: {})",
                               lines, first_bad_line, first_bad_why));
    else
      rec.error(0, fmt::format("no samples: {} lines, {} blank, {} header lines, {} samples all unusable", lines,
                               blank, headers + column_headers, raw.size()));
    return rec;
  }
  if (ticks_per_s != 1000)
    rec.warn(0, fmt::format("the times step by ~{:.0f} from sample to sample: micros() (µs), not millis() — as "
                            "milliseconds no coast would hold two samples; read as µs (if they are milliseconds "
                            "after all: --time-unit ms)",
                            median_step(raw.t)));
  rec.note(0, text::summary_with_counts(fmt::format("{} samples from {} lines", rec.size(), lines),
                                        {{headers, "PuTTY header"},
                                         {column_headers, "column header"},
                                         {blank, "blank"},
                                         {garbled, "garbled"}},
                                        timeline));
  return rec;
}

Recording read_arduino_text_file(const std::string& path, const ArduinoTextOptions& options) {
  return text::read_text_file(path, options, [](std::string_view bytes, const std::string& source, const auto& o) {
    return read_arduino_text(bytes, source, o);
  });
}

}  // namespace spindown
