#include "spindown/delimited_text.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <span>
#include <fmt/format.h>
#include <system_error>
#include <vector>

#include "spindown/column_guess.hpp"
#include "spindown/csv_fields.hpp"
#include "spindown/ascii_lower.hpp"
#include "spindown/text_support.hpp"
#include "spindown/trim.hpp"

namespace spindown {

namespace {

// A field in single quotes ('time'), as some loggers write them: without them.
std::string_view unquote_single(std::string_view s) {
  if (s.size() >= 2 && s.front() == '\'' && s.back() == '\'') s = trim(s.substr(1, s.size() - 2));
  return s;
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

std::string list_columns(const std::vector<ColumnName>& cols) {
  std::string out;
  for (std::size_t i = 0; i < cols.size(); ++i)
    out += fmt::format("{}{} '{}'", i ? ", " : "", i + 1, cols[i].name);
  return out;
}

bool all_digits(std::string_view s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

// The column the user named: index or header name. -1 and *why when there is none.
int resolve_named(const std::string& spec, const std::vector<ColumnName>& cols, bool have_header, std::string* why) {
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
  const std::string want = ascii_lower(trim(spec));
  int found = -1;
  for (std::size_t i = 0; i < cols.size(); ++i) {
    if (ascii_lower(cols[i].name) == want || cols[i].base == want) {
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

}  // namespace

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
  if (!time_column.empty() && ascii_lower(time_column) == ascii_lower(value_column))
    return fail(fmt::format("time and value are both column '{}'", time_column));
  if (delimiter != 0 && delimiter != ',' && delimiter != ';' && delimiter != '\t' && delimiter != ' ')
    return fail(fmt::format("delimiter '{}' is not one of ',', ';', tab or blank", delimiter));
  if (max_line_reports == 0) return fail("max_line_reports must be at least 1");
  if (!std::isfinite(value_scale) || value_scale <= 0)
    return fail(fmt::format("value scale {} is not a positive number", value_scale));
  return true;
}

bool header_needs_delimited_reader(std::string_view line) {
  char delim = ' ';
  for (char cand : {'\t', ';', ','})
    if (line.find(cand) != std::string_view::npos) {
      delim = cand;
      break;
    }
  CsvFieldSplitter splitter;
  std::vector<std::string_view> fields;
  splitter.split(line, delim, fields);
  if (fields.size() < 2) return false;
  for (const auto f : fields) {
    double x;
    std::string_view w;
    if (f.empty() || parse_number(f, delim != ',', x, w)) return false;
  }
  for (const auto f : fields) {
    const ColumnName c = describe_column(unquote_single(f));
    if (unknown_value_unit(c)) return true;
    if (const auto t = implied_time_unit(c); t && *t != TimeUnit::ms) return true;
    const auto v = implied_value_unit(c);
    if (v && (v->quantity != Quantity::back_emf_volts || v->scale != 1)) return true;
    if (!v && !likely_value_unit(c).empty() && likely_value_unit(c) != "V") return true;
  }
  return false;
}

Recording read_delimited_text(std::string_view text, std::string source, const DelimitedTextOptions& options) {
  Recording rec;
  rec.source = std::move(source);
  if (!text::readable_text(text, options, "delimited text", rec)) return rec;

  // Content lines (not blank, not a comment, not a PuTTY header), as views into text. A row of
  // separators alone (";;;;", as a spreadsheet saves its empty rows) is blank.
  struct Line {
    std::int64_t number;
    std::string_view text;
  };
  std::vector<Line> content;
  content.reserve(text.size() / 12 + 1);
  std::size_t blank = 0, comments = 0, headers = 0;
  const std::int64_t lines = text::for_each_line(text, [&](std::int64_t n, std::string_view line) {
    const std::string_view t = trim(line);
    if (t.empty() || t.find_first_not_of(" \t;,") == std::string_view::npos) ++blank;
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
  // A comma that is not the delimiter is a decimal comma ("2,81": a European spreadsheet's CSV or
  // "Unicode text").
  const bool decimal_comma = delim != ',';
  const std::string_view delim_name = delim == '\t' ? "tab" : delim == ' ' ? "blanks" : std::string_view(&delim, 1);

  CsvFieldSplitter splitter;
  std::vector<std::string_view> fields;
  fields.reserve(16);
  const auto split = [&](std::string_view line) {
    splitter.split(line, delim, fields);
    for (auto& f : fields) f = unquote_single(f);
  };
  const auto is_number = [&](std::string_view f) {
    double x;
    std::string_view w;
    return parse_number(f, decimal_comma, x, w);
  };
  // A first line cut short (a logger started mid-line: the last fields of a row, all numbers) does
  // not set the table's width: with fewer fields than most of the first lines have, it is skipped
  // and said.
  if (content.size() > 2 && !options.header.value_or(false)) {
    std::vector<std::size_t> widths;
    for (std::size_t i = 1; i < probe; ++i) {
      split(content[i].text);
      widths.push_back(fields.size());
    }
    std::nth_element(widths.begin(), widths.begin() + std::ptrdiff_t(widths.size() / 2), widths.end());
    const std::size_t usual = widths[widths.size() / 2];
    split(content.front().text);
    if (fields.size() < usual && std::all_of(fields.begin(), fields.end(), is_number)) {
      rec.warn(content.front().number,
               fmt::format("{} fields where the rows below have {}: a line cut at the start of the recording; skipped",
                           fields.size(), usual));
      content.erase(content.begin());
    }
  }
  split(content.front().text);
  bool have_header = false;
  if (options.header) {
    have_header = *options.header;
  } else {
    have_header = !std::all_of(fields.begin(), fields.end(), is_number);
  }
  std::vector<ColumnName> cols;
  for (std::size_t i = 0; i < fields.size(); ++i)
    cols.push_back(have_header ? describe_column(fields[i]) : ColumnName{fmt::format("{}", i + 1), "", ""});
  // A row of units under the names ("s;rpm", "[ms]\t[V]"): no number in it and a unit read.
  std::size_t first_data = have_header ? 1 : 0, unit_rows = 0;
  if (have_header && content.size() > 1) {
    split(content[1].text);
    std::vector<std::string> units;
    for (const auto f : fields) units.push_back(unit_cell(f));
    const bool units_row = std::none_of(fields.begin(), fields.end(), is_number) &&
                           std::any_of(units.begin(), units.end(), [](const std::string& u) { return !u.empty(); }) &&
                           std::all_of(fields.begin(), fields.end(), [&](std::string_view f) {
                             return f.empty() || !unit_cell(f).empty();
                           });
    if (units_row) {
      for (std::size_t i = 0; i < cols.size() && i < units.size(); ++i)
        if (cols[i].unit.empty() && !units[i].empty()) cols[i].unit = units[i];
      first_data = 2;
      unit_rows = 1;
    }
  }
  // Names and units go into messages (and JSON): bytes that are not UTF-8 (a header in a legacy
  // encoding read raw) are written \xNN there, once, here.
  for (ColumnName& c : cols) {
    c.name = text::escape_invalid_utf8(c.name);
    c.unit = text::escape_invalid_utf8(c.unit);
  }

  auto give_up = [&](std::string message) {
    rec.error(0, std::move(message));
    rec.lines_skipped = rec.lines_read;
    return rec;
  };
  if (cols.size() < 2)
    return give_up(fmt::format("no samples: line {} has {} field (delimiter {}); need a time and a value column",
                               content.front().number, cols.size(), delim_name));

  // What the numbers say when the names do not: the table's first rows, column by column.
  std::optional<ColumnGuess> guessed;
  const auto guess = [&]() -> const ColumnGuess& {
    if (!guessed) {
      constexpr std::size_t max_rows = 100'000;
      std::vector<std::vector<double>> table(cols.size());
      for (std::size_t i = first_data; i < content.size() && i - first_data < max_rows; ++i) {
        split(content[i].text);
        for (std::size_t c = 0; c < cols.size(); ++c) {
          double x = std::numeric_limits<double>::quiet_NaN();
          std::string_view w;
          if (c >= fields.size() || !parse_number(fields[c], decimal_comma, x, w))
            x = std::numeric_limits<double>::quiet_NaN();
          table[c].push_back(x);
        }
      }
      guessed = guess_columns(table);
    }
    return *guessed;
  };
  const auto proposal = [&]() {
    const auto p = column_proposal(guess());
    return p ? "; " + *p : std::string();
  };

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
  const std::string unnamed = have_header ? "" : " (the file has no header row)";
  if (tcol < 0) {
    auto c = candidates([](const ColumnName& col) { return is_time_name(col); }, vcol);
    if (c.size() == 1) tcol = c[0];
    else if (c.size() > 1)
      return give_up(fmt::format("columns {} could each be the time; name one (time column)", names_of(c)));
    else if (cols.size() == 2) tcol = vcol == 0 ? 1 : 0;
    else if (const auto p = column_proposal(guess()))
      return give_up(fmt::format("cannot tell which of the {} columns is the time{}: {}", cols.size(), unnamed, *p));
    else
      return give_up(fmt::format("cannot tell which of the {} columns is the time{} ({}); name it (time column)",
                                 cols.size(), unnamed, list_columns(cols)));
  }
  if (vcol < 0) {
    auto c = candidates([](const ColumnName& col) { return is_value_name(col); }, tcol);
    if (c.size() == 1) vcol = c[0];
    else if (c.size() > 1)
      return give_up(fmt::format("columns {} could each be the value; name one (value column){}", names_of(c),
                                 proposal()));
    else if (cols.size() == 2) vcol = tcol == 0 ? 1 : 0;
    else if (const auto p = column_proposal(guess()); p && guess().time == tcol)
      return give_up(fmt::format("cannot tell which of the {} columns is the value{}: {}", cols.size(), unnamed, *p));
    else
      return give_up(fmt::format("cannot tell which of the {} columns is the value{} ({}); name it (value column)",
                                 cols.size(), unnamed, list_columns(cols)));
  }

  // Quantity, and the factor that turns a reading into it (mV: 0.001 V).
  std::string quantity_from = "given";
  std::string value_unit_name;
  double value_scale = 1;
  const ColumnName& value_col = cols[vcol];
  if (options.quantity) {
    rec.quantity = *options.quantity;
    value_scale = options.value_scale;
  } else if (auto u = implied_value_unit(value_col)) {
    rec.quantity = u->quantity;
    value_scale = u->scale;
    value_unit_name = u->name;
    quantity_from = "from the header";
  } else if (!have_header) {
    rec.quantity = Quantity::back_emf_volts;
    quantity_from = "assumed: no header";
  } else {
    const std::string_view likely = likely_value_unit(value_col);
    const std::string option = likely.empty() ? std::string("--value-unit V, rpm or rad/s")
                                              : fmt::format("--value-unit {}", likely);
    if (unknown_value_unit(value_col))
      return give_up(fmt::format("value column '{}': its unit '{}' is not one spindown reads ({}); if the readings "
                                 "are one of those under another name, say which: {}",
                                 value_col.name, value_col.unit, value_units_read(), option));
    return give_up(fmt::format("cannot tell the unit of value column '{}' (V, rpm or rad/s); name it: {}",
                               value_col.name, option));
  }
  if (!options.time_unit && !cols[tcol].unit.empty() && !parse_time_unit(cols[tcol].unit))
    return give_up(fmt::format("time column '{}': its unit '{}' is not one spindown reads (s, ms, us); convert the "
                               "times or name their unit: --time-unit s, ms or us",
                               cols[tcol].name, cols[tcol].unit));

  // Rows.
  text::LineReporter reporter(rec, options.max_line_reports);
  text::RawSamples raw(text);
  raw.reserve(content.size());
  std::size_t bad = 0;
  const std::size_t need = static_cast<std::size_t>(std::max(tcol, vcol)) + 1;
  for (std::size_t i = first_data; i < content.size(); ++i) {
    const Line& line = content[i];
    split(line.text);
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
    raw.add(line.number, line.text.data(), t, v * value_scale, false);
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
    bool integral = false;
    double step = 0;
    unit = time_unit_from_values(std::span<const double>(raw.t.data(), std::min<std::size_t>(raw.size(), 65)),
                                 &integral, &step);
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

  const std::string value_unit =
      value_scale != 1 && !value_unit_name.empty()
          ? fmt::format("{} read as {}", value_unit_name, quantity_unit(rec.quantity))
          : value_scale != 1 ? fmt::format("{} x {:g}", quantity_unit(rec.quantity), value_scale)
                             : std::string(quantity_unit(rec.quantity));
  const std::string columns = fmt::format("time = column {} '{}' in {} ({}), value = column {} '{}' in {} ({}), "
                                          "delimiter {}",
                                          tcol + 1, cols[tcol].name, time_unit_name(unit), unit_from, vcol + 1,
                                          cols[vcol].name, value_unit, quantity_from, delim_name);
  if (rec.empty()) {
    rec.error(0, fmt::format("no samples: {} lines, none with a usable time and value ({})", lines, columns));
    return rec;
  }
  rec.note(0, text::summary_with_counts(fmt::format("{} samples from {} lines; {}", rec.size(), lines, columns),
                                        {{have_header ? 1u : 0u, "header row"},
                                         {unit_rows, "units row"},
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
