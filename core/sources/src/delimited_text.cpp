#include "spindown/delimited_text.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fmt/format.h>
#include <system_error>
#include <vector>

#include "spindown/text_support.hpp"

namespace spindown {

std::string_view time_unit_name(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return "s";
    case TimeUnit::ms: return "ms";
    case TimeUnit::us: return "us";
  }
  return "?";
}

namespace {

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c); });
  return out;
}

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  if (s.size() >= 2 && ((s.front() == '"' && s.back() == '"') || (s.front() == '\'' && s.back() == '\''))) {
    s = s.substr(1, s.size() - 2);
    while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
    while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  }
  return s;
}

// Fields of one line into out (reused: no allocation once it has grown).
void split(std::string_view line, char delimiter, std::vector<std::string_view>& out) {
  out.clear();
  if (delimiter == ' ') {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && is_blank(line[i])) ++i;
      if (i == line.size()) break;
      std::size_t j = i;
      while (j < line.size() && !is_blank(line[j])) ++j;
      out.push_back(trim(line.substr(i, j - i)));
      i = j;
    }
    return;
  }
  std::size_t start = 0;
  for (;;) {
    const std::size_t at = line.find(delimiter, start);
    out.push_back(trim(line.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start)));
    if (at == std::string_view::npos) break;
    start = at + 1;
  }
}

// A number field; decimal_comma accepts "2,81" (semicolon CSV from European spreadsheets).
bool parse_number(std::string_view field, bool decimal_comma, double& out, std::string_view& why) {
  if (field.empty()) {
    why = "empty";
    return false;
  }
  std::array<char, 64> buf;
  if (field.size() >= buf.size()) {
    why = "too long to be a number";
    return false;
  }
  std::size_t n = 0;
  for (char c : field) buf[n++] = (decimal_comma && c == ',') ? '.' : c;
  const char* b = buf.data();
  const char* e = buf.data() + n;
  if (*b == '+') ++b;
  auto [p, ec] = std::from_chars(b, e, out);
  if (ec == std::errc::invalid_argument || p != e) {
    why = "not a number";
    return false;
  }
  if (ec == std::errc::result_out_of_range) {
    why = "out of range";
    return false;
  }
  if (!std::isfinite(out)) {
    why = "NaN or infinite";
    return false;
  }
  return true;
}

struct Column {
  std::string name;  // as written
  std::string base;  // lower case, unit removed: "time (s)" -> "time"
  std::string unit;  // lower case: "s", "ms", "v", "rpm", "rad/s" or empty
};

bool is_unit_word(std::string_view u) { return parse_time_unit(u) || parse_quantity(u); }

Column describe_column(std::string_view name) {
  Column c;
  c.name = text::escape_invalid_utf8(name);  // shown in messages, which must stay UTF-8
  std::string l = lower(name);
  const std::size_t open = l.find_first_of("([");
  if (open != std::string::npos) {
    const std::size_t close = l.find_first_of(")]", open);
    c.unit = std::string(trim(std::string_view(l).substr(open + 1, close == std::string::npos ? std::string::npos
                                                                                             : close - open - 1)));
    c.base = std::string(trim(std::string_view(l).substr(0, open)));
  } else {
    c.base = l;
    const std::size_t us = l.rfind('_');
    if (us != std::string::npos && us > 0 && is_unit_word(std::string_view(l).substr(us + 1))) {
      c.unit = l.substr(us + 1);
      c.base = l.substr(0, us);
    }
  }
  return c;
}

constexpr std::array time_names{"time", "t", "millis", "ms", "micros", "us", "µs", "timestamp", "seconds", "sec", "s"};
constexpr std::array value_names{"volts", "volt", "voltage", "v", "u", "emf", "back_emf", "back-emf", "backemf",
                                 "bemf", "a0", "rpm", "omega", "w", "ω", "angular_velocity", "angular_speed",
                                 "speed", "value", "reading"};

template <std::size_t N>
bool in(const std::array<const char*, N>& names, std::string_view s) {
  return std::any_of(names.begin(), names.end(), [&](const char* n) { return s == n; });
}

std::string list_columns(const std::vector<Column>& cols) {
  std::string out;
  for (std::size_t i = 0; i < cols.size(); ++i)
    out += fmt::format("{}{} '{}'", i ? ", " : "", i + 1, cols[i].name);
  return out;
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// The column the user named: index or header name. -1 and *why when there is none.
int resolve_named(const std::string& spec, const std::vector<Column>& cols, bool have_header, std::string* why) {
  if (all_digits(spec)) {
    const unsigned long k = std::stoul(spec);
    if (k >= 1 && k <= cols.size()) return static_cast<int>(k - 1);
    *why = fmt::format("column {} does not exist: the file has {} columns", spec, cols.size());
    return -1;
  }
  if (!have_header) {
    *why = fmt::format("column '{}' is named but the file has no header row; give its 1-based index", spec);
    return -1;
  }
  const std::string want = lower(spec);
  int found = -1;
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (lower(cols[i].name) == want || cols[i].base == want) {
      if (found >= 0) {
        *why = fmt::format("column name '{}' matches both column {} and column {}; give the index", spec, found + 1,
                           i + 1);
        return -1;
      }
      found = static_cast<int>(i);
    }
  }
  if (found < 0) *why = fmt::format("no column named '{}' (columns: {})", spec, list_columns(cols));
  return found;
}

std::optional<TimeUnit> implied_time_unit(const Column& c) {
  if (!c.unit.empty()) return parse_time_unit(c.unit);
  return parse_time_unit(c.base);  // "millis", "ms", "seconds"; "time" gives nothing
}

std::optional<Quantity> implied_quantity(const Column& c) {
  if (!c.unit.empty()) return parse_quantity(c.unit);
  const std::string& b = c.base;
  if (b == "volts" || b == "volt" || b == "voltage" || b == "v" || b == "u" || b == "emf" || b == "back_emf" ||
      b == "back-emf" || b == "backemf" || b == "bemf" || b == "a0")
    return Quantity::back_emf_volts;
  if (b == "rpm") return Quantity::rpm;
  if (b == "omega" || b == "w" || b == "ω" || b == "angular_velocity" || b == "angular_speed")
    return Quantity::rad_per_s;
  return std::nullopt;
}

}  // namespace

std::optional<TimeUnit> parse_time_unit(std::string_view unit) {
  const std::string u = lower(unit);
  if (u == "s" || u == "sec" || u == "secs" || u == "second" || u == "seconds") return TimeUnit::s;
  if (u == "ms" || u == "msec" || u == "millis" || u == "millisecond" || u == "milliseconds") return TimeUnit::ms;
  if (u == "us" || u == "µs" || u == "usec" || u == "micros" || u == "microsecond" || u == "microseconds")
    return TimeUnit::us;
  return std::nullopt;
}

double time_units_per_second(TimeUnit unit) {
  switch (unit) {
    case TimeUnit::s: return 1.0;
    case TimeUnit::ms: return 1e3;
    case TimeUnit::us: return 1e6;
  }
  return 1.0;
}

bool DelimitedTextOptions::names_columns() const {
  return !time_column.empty() || !value_column.empty() || time_unit.has_value() || quantity.has_value() ||
         delimiter != 0 || header.has_value();
}

bool DelimitedTextOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  for (const std::string* c : {&time_column, &value_column}) {
    if (all_digits(*c) && (c->size() > 6 || std::stoul(*c) == 0))
      return fail(fmt::format("column index '{}' must be between 1 and 999999", *c));
  }
  if (!time_column.empty() && lower(time_column) == lower(value_column))
    return fail(fmt::format("time and value are both column '{}'", time_column));
  if (delimiter != 0 && delimiter != ',' && delimiter != ';' && delimiter != '\t' && delimiter != ' ')
    return fail(fmt::format("delimiter '{}' is not one of ',', ';', tab or blank", delimiter));
  if (max_line_reports == 0) return fail("max_line_reports must be at least 1");
  return true;
}

Recording read_delimited_text(std::string_view text, std::string source, const DelimitedTextOptions& options) {
  Recording rec;
  rec.source = std::move(source);
  if (!text::readable_text(text, options, "delimited text", rec)) return rec;

  // Content lines (not blank, not a comment, not a PuTTY header), as views into text.
  struct Line {
    std::int64_t number;
    std::string_view text;
  };
  std::vector<Line> content;
  content.reserve(text.size() / 12 + 1);
  std::size_t blank = 0, comments = 0, headers = 0;
  const std::int64_t lines = text::for_each_line(text, [&](std::int64_t n, std::string_view line) {
    const std::string_view t = trim(line);
    if (t.empty()) ++blank;
    else if (t.front() == '#') ++comments;
    else if (t.starts_with("=~=~=~")) {
      ++headers;
      rec.note(n, text::putty_header_note(line));
    } else content.push_back({n, line});
  });
  rec.lines_read = static_cast<std::size_t>(lines);
  if (content.empty()) {
    rec.error(0, fmt::format("no samples: {} lines, none with data ({} blank, {} comments)", lines, blank, comments));
    rec.lines_skipped = rec.lines_read;
    return rec;
  }

  // Delimiter: the first of tab, ';', ',' found on nearly every one of the first lines.
  char delim = options.delimiter;
  const std::size_t probe = std::min<std::size_t>(content.size(), 20);
  if (delim == 0) {
    delim = ' ';
    for (char cand : {'\t', ';', ','}) {
      std::size_t with = 0;
      for (std::size_t i = 0; i < probe; ++i) with += content[i].text.find(cand) != std::string_view::npos;
      if (with * 5 >= probe * 4) {
        delim = cand;
        break;
      }
    }
  }
  const bool decimal_comma = delim == ';';
  const std::string_view delim_name = delim == '\t' ? "tab" : delim == ' ' ? "blanks" : std::string_view(&delim, 1);

  std::vector<std::string_view> fields;
  fields.reserve(16);
  split(content.front().text, delim, fields);
  bool have_header = false;
  if (options.header) {
    have_header = *options.header;
  } else {
    double x;
    std::string_view w;
    have_header = std::any_of(fields.begin(), fields.end(),
                              [&](std::string_view f) { return !parse_number(f, decimal_comma, x, w); });
  }
  std::vector<Column> cols;
  for (std::size_t i = 0; i < fields.size(); ++i)
    cols.push_back(have_header ? describe_column(fields[i]) : Column{fmt::format("{}", i + 1), "", ""});

  auto give_up = [&](std::string message) {
    rec.error(0, std::move(message));
    rec.lines_skipped = rec.lines_read;
    return rec;
  };
  if (cols.size() < 2)
    return give_up(fmt::format("no samples: line {} has {} field (delimiter {}); need a time and a value column",
                               content.front().number, cols.size(), delim_name));

  // Columns.
  int tcol = -1, vcol = -1;
  std::string why;
  if (!options.time_column.empty()) {
    tcol = resolve_named(options.time_column, cols, have_header, &why);
    if (tcol < 0) return give_up("time column: " + why);
  }
  if (!options.value_column.empty()) {
    vcol = resolve_named(options.value_column, cols, have_header, &why);
    if (vcol < 0) return give_up("value column: " + why);
  }
  if (tcol >= 0 && tcol == vcol) return give_up(fmt::format("time and value are both column {}", tcol + 1));
  auto candidates = [&](auto pred, int exclude) {
    std::vector<int> out;
    for (std::size_t i = 0; i < cols.size(); ++i)
      if (static_cast<int>(i) != exclude && pred(cols[i])) out.push_back(static_cast<int>(i));
    return out;
  };
  auto names_of = [&](const std::vector<int>& idx) {
    std::string out;
    for (std::size_t k = 0; k < idx.size(); ++k) out += fmt::format("{}'{}'", k ? " and " : "", cols[idx[k]].name);
    return out;
  };
  if (tcol < 0) {
    auto c = candidates([](const Column& col) { return in(time_names, col.base); }, vcol);
    if (c.size() == 1) tcol = c[0];
    else if (c.size() > 1)
      return give_up(fmt::format("columns {} could each be the time; name one (time column)", names_of(c)));
    else if (cols.size() == 2) tcol = vcol == 0 ? 1 : 0;
    else
      return give_up(fmt::format("cannot tell which of the {} columns is the time ({}); name it (time column)",
                                 cols.size(), list_columns(cols)));
  }
  if (vcol < 0) {
    auto c = candidates([](const Column& col) { return in(value_names, col.base) || implied_quantity(col); }, tcol);
    if (c.size() == 1) vcol = c[0];
    else if (c.size() > 1)
      return give_up(fmt::format("columns {} could each be the value; name one (value column)", names_of(c)));
    else if (cols.size() == 2) vcol = tcol == 0 ? 1 : 0;
    else
      return give_up(fmt::format("cannot tell which of the {} columns is the value ({}); name it (value column)",
                                 cols.size(), list_columns(cols)));
  }

  // Quantity.
  std::string quantity_from = "given";
  if (options.quantity) {
    rec.quantity = *options.quantity;
  } else if (auto q = implied_quantity(cols[vcol])) {
    rec.quantity = *q;
    quantity_from = "from the header";
  } else if (!have_header) {
    rec.quantity = Quantity::back_emf_volts;
    quantity_from = "assumed: no header";
  } else {
    return give_up(fmt::format("cannot tell the unit of value column '{}' (V, rpm or rad/s); name it",
                               cols[vcol].name));
  }

  // Rows.
  text::LineReporter reporter(rec, options.max_line_reports);
  text::RawSamples raw(text);
  raw.reserve(content.size());
  std::size_t bad = 0;
  const std::size_t need = static_cast<std::size_t>(std::max(tcol, vcol)) + 1;
  for (std::size_t i = have_header ? 1 : 0; i < content.size(); ++i) {
    const Line& line = content[i];
    split(line.text, delim, fields);
    if (fields.size() < need) {
      ++bad;
      reporter.warn(line.number, fmt::format("{}: {} fields, column {} is missing; skipped",
                                             text::quote_line(line.text), fields.size(), need));
      continue;
    }
    double t = 0, v = 0;
    std::string_view w;
    if (!parse_number(fields[tcol], decimal_comma, t, w)) {
      ++bad;
      reporter.warn(line.number, fmt::format("{}: time '{}' is {}; skipped", text::quote_line(line.text),
                                             text::escape_invalid_utf8(fields[tcol].substr(0, 40)), w));
      continue;
    }
    if (!parse_number(fields[vcol], decimal_comma, v, w)) {
      ++bad;
      reporter.warn(line.number, fmt::format("{}: value '{}' is {}; skipped", text::quote_line(line.text),
                                             text::escape_invalid_utf8(fields[vcol].substr(0, 40)), w));
      continue;
    }
    raw.add(line.number, line.text.data(), t, v, false);
  }

  // Time unit.
  TimeUnit unit = TimeUnit::s;
  std::string unit_from = "given";
  if (options.time_unit) {
    unit = *options.time_unit;
  } else if (auto u = implied_time_unit(cols[tcol])) {
    unit = *u;
    unit_from = "from the header";
  } else {
    // Whole numbers with steps of at least 1 are counter ticks: ms, or µs for big steps.
    std::vector<double> steps;
    bool integral = true;
    for (std::size_t i = 0; i < raw.size() && i < 65; ++i) {
      integral = integral && raw.t[i] == std::floor(raw.t[i]);
      if (i > 0 && raw.t[i] > raw.t[i - 1]) steps.push_back(raw.t[i] - raw.t[i - 1]);
    }
    double step = 0;
    if (!steps.empty()) {
      std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
      step = steps[steps.size() / 2];
    }
    unit = integral && step >= 1 ? (step >= 5000 ? TimeUnit::us : TimeUnit::ms) : TimeUnit::s;
    unit_from = "assumed";
    rec.note(0, fmt::format("time unit not given: times {} with steps of ~{:g}, read as {}; name the unit if "
                            "that is wrong",
                            integral ? "are whole numbers" : "have fractions", step, time_unit_name(unit)));
  }

  text::TimelineRules rules;
  rules.units_per_s = time_units_per_second(unit);
  rules.unit = time_unit_name(unit);
  rules.wrap = 0;
  rules.reset_min_back = rules.units_per_s;
  rules.drop_cut_first = false;
  const text::TimelineCounts timeline = text::build_timeline(raw, rules, rec, reporter);
  reporter.finish();
  text::sort_by_line(rec);
  rec.lines_skipped = rec.lines_read - rec.size();

  const std::string columns = fmt::format("time = column {} '{}' in {} ({}), value = column {} '{}' in {} ({}), "
                                          "delimiter {}",
                                          tcol + 1, cols[tcol].name, time_unit_name(unit), unit_from, vcol + 1,
                                          cols[vcol].name, quantity_unit(rec.quantity), quantity_from, delim_name);
  if (rec.empty()) {
    rec.error(0, fmt::format("no samples: {} lines, none with a usable time and value ({})", lines, columns));
    return rec;
  }
  rec.note(0, text::summary_with_counts(fmt::format("{} samples from {} lines; {}", rec.size(), lines, columns),
                                        {{have_header ? 1u : 0u, "header row"},
                                         {headers, "PuTTY header"},
                                         {comments, "comment"},
                                         {blank, "blank"},
                                         {bad, "unusable"}},
                                        timeline));
  return rec;
}

Recording read_delimited_text_file(const std::string& path, const DelimitedTextOptions& options) {
  return text::read_text_file(path, options, [](std::string_view bytes, const std::string& source, const auto& o) {
    return read_delimited_text(bytes, source, o);
  });
}

}  // namespace spindown
