#include "spindown/delimited_text.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
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
         delimiter != 0 || header.has_value() || period_ms.has_value();
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
  if (period_ms && !(std::isfinite(*period_ms) && *period_ms > 0))
    return fail(fmt::format("period {} ms is not a positive number", *period_ms));
  if (period_ms && (!time_column.empty() || time_unit))
    return fail("a period (--period-ms) stands for the time column: give it, or the time column and its unit");
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

const std::vector<std::string_view>& DelimitedRowReader::split(std::string_view line, char delimiter) {
  splitter_.split(line, delimiter, fields_);
  for (auto& f : fields_) f = unquote_single(f);
  return fields_;
}

DelimitedRowReader::Row DelimitedRowReader::read(std::string_view line) {
  Row row;
  split(line, layout_.delimiter);
  const std::size_t need = static_cast<std::size_t>(std::max(layout_.time_column, layout_.value_column)) + 1;
  if (fields_.size() < need) {
    row.why = fmt::format("{} fields, column {} is missing", fields_.size(), need);
    return row;
  }
  std::string_view w;
  const std::string_view tf = fields_[static_cast<std::size_t>(layout_.time_column)];
  if (!parse_number(tf, layout_.decimal_comma, row.time, w)) {
    row.why = fmt::format("time '{}' is {}", text::escape_invalid_utf8(tf.substr(0, 40)), w);
    return row;
  }
  const std::string_view vf = fields_[static_cast<std::size_t>(layout_.value_column)];
  if (!parse_number(vf, layout_.decimal_comma, row.value, w)) {
    row.why = fmt::format("value '{}' is {}", text::escape_invalid_utf8(vf.substr(0, 40)), w);
    return row;
  }
  row.value *= layout_.value_scale;
  row.ok = true;
  return row;
}

namespace {

// One delimited-text file read step by step (read_delimited_text): its content lines, the
// delimiter, the header, the columns, the value's and the time's units, then the rows. A step that
// cannot go on returns the reason, which read_delimited_text reports as the file's error.
class DelimitedReader {
 public:
  DelimitedReader(std::string_view text, const DelimitedTextOptions& options, Recording& rec)
      : text_(text), o_(options), rec_(rec), raw_(text) {}

  void collect_lines();
  bool empty() const { return content_.empty(); }
  std::string nothing_in_it() const {
    return fmt::format("no samples: {} lines, none with data ({} blank, {} comments)", lines_, blank_, comments_);
  }
  void choose_delimiter();
  void skip_cut_first_line();
  void read_header();
  std::optional<std::string> choose_columns();
  std::optional<std::string> choose_value_unit();
  void read_rows();
  void choose_time_unit_and_finish();
  bool read_scope_header();
  const DelimitedLayout& layout() const { return rows_.layout(); }

 private:
  struct Line {
    std::int64_t number;
    std::string_view text;
  };
  void split(std::string_view line) { fields_ = rows_.split(line, delim_); }
  bool is_number(std::string_view f) const {
    double x;
    std::string_view w;
    return parse_number(f, decimal_comma_, x, w);
  }
  const ColumnGuess& guess();
  std::string proposal() {
    const auto p = full_proposal();
    return p ? "; " + *p : std::string();
  }
  // column_proposal, with the value's unit when the header would not give it (a header whose value
  // column names no unit asks for one next): every option a refusal proposes, at once.
  std::optional<std::string> full_proposal() {
    auto p = column_proposal(guess());
    const int v = guess().value;
    if (p && have_header_ && v >= 0 && static_cast<std::size_t>(v) < cols_.size() && guess().value_peak <= 30 &&
        !o_.quantity && !implied_value_unit(cols_[static_cast<std::size_t>(v)]) &&
        p->find("--value-unit") == std::string::npos)
      *p += " --value-unit V";
    return p;
  }

  std::string_view text_;
  const DelimitedTextOptions& o_;
  Recording& rec_;
  std::vector<Line> content_;
  std::size_t blank_ = 0, comments_ = 0, headers_ = 0;
  std::int64_t lines_ = 0;
  char delim_ = ' ';
  bool decimal_comma_ = false;
  std::string_view delim_name_;
  DelimitedRowReader rows_{DelimitedLayout{}};  // splits every line; reads the rows once the layout is chosen
  std::vector<std::string_view> fields_;
  std::vector<ColumnName> cols_;
  bool have_header_ = false;
  std::size_t first_data_ = 0, unit_rows_ = 0;
  std::optional<ColumnGuess> guessed_;
  int tcol_ = -1, vcol_ = -1;
  struct ScopeTiming {
    double start_s, increment_s;
  };
  std::optional<ScopeTiming> scope_;  // an oscilloscope's CSV: sample k is at Start + k·Increment
  std::string quantity_from_ = "given", value_unit_name_;
  double value_scale_ = 1;
  text::RawSamples raw_;
  std::size_t bad_ = 0;
  std::optional<text::LineReporter> reporter_;
};

// Content lines (not blank, not a comment, not a PuTTY header), as views into the text. A row of
// separators alone (";;;;", as a spreadsheet saves its empty rows) is blank.
void DelimitedReader::collect_lines() {
  content_.reserve(text_.size() / 12 + 1);
  lines_ = text::for_each_line(text_, [&](std::int64_t n, std::string_view line) {
    const std::string_view t = trim(line);
    if (t.empty() || t.find_first_not_of(" \t;,") == std::string_view::npos) ++blank_;
    else if (t.front() == '#') ++comments_;
    else if (t.starts_with("=~=~=~")) {
      ++headers_;
      rec_.note(n, text::putty_header_note(line));
    } else content_.push_back({n, line});
  });
  rec_.lines_read = static_cast<std::size_t>(lines_);
}

// The delimiter: the one given, else the first of tab, ';', ',' found on nearly every one of the
// first lines, else blanks. A comma that is not the delimiter is a decimal comma ("2,81": a
// European spreadsheet's CSV or "Unicode text").
void DelimitedReader::choose_delimiter() {
  delim_ = o_.delimiter;
  const std::size_t probe = std::min<std::size_t>(content_.size(), 20);
  if (delim_ == 0) {
    delim_ = ' ';
    for (char cand : {'\t', ';', ','}) {
      std::size_t with = 0;
      for (std::size_t i = 0; i < probe; ++i) with += content_[i].text.find(cand) != std::string_view::npos;
      if (with * 5 >= probe * 4) {
        delim_ = cand;
        break;
      }
    }
  }
  decimal_comma_ = delim_ != ',';
  // A comma CSV whose numbers are quoted with decimal commas ("6,010","2,65": Google Sheets or
  // LibreOffice in a German locale): the quotes keep the fields apart, the comma in them is decimal.
  if (delim_ == ',') {
    std::size_t comma_numbers = 0, point_numbers = 0;
    for (std::size_t i = 0; i < probe; ++i) {
      for (const std::string_view f : rows_.split(content_[i].text, ',')) {
        double x;
        std::string_view w;
        if (f.find(',') != std::string_view::npos && parse_number(f, true, x, w)) ++comma_numbers;
        else if (f.find('.') != std::string_view::npos && parse_number(f, false, x, w)) ++point_numbers;
      }
    }
    decimal_comma_ = comma_numbers > 0 && point_numbers == 0;
  }
  delim_name_ = delim_ == '\t' ? "tab" : delim_ == ' ' ? "blanks" : std::string_view(&delim_, 1);
}

// A first line cut short (a logger started mid-line: the last fields of a row, all numbers) does
// not set the table's width: with fewer fields than most of the first lines have, it is skipped
// and said.
void DelimitedReader::skip_cut_first_line() {
  if (content_.size() <= 2 || o_.header.value_or(false)) return;
  const std::size_t probe = std::min<std::size_t>(content_.size(), 20);
  std::vector<std::size_t> widths;
  for (std::size_t i = 1; i < probe; ++i) {
    split(content_[i].text);
    widths.push_back(fields_.size());
  }
  std::nth_element(widths.begin(), widths.begin() + std::ptrdiff_t(widths.size() / 2), widths.end());
  const std::size_t usual = widths[widths.size() / 2];
  split(content_.front().text);
  if (fields_.size() < usual && std::all_of(fields_.begin(), fields_.end(), [&](auto f) { return is_number(f); })) {
    rec_.warn(content_.front().number,
              fmt::format("{} fields where the rows below have {}: a line cut at the start of the recording; skipped",
                          fields_.size(), usual));
    content_.erase(content_.begin());
  }
}

// The header (a first row with a non-number, unless told), a row of units under it ("s;rpm",
// "[ms]\t[V]": no number in it and a unit read), and the columns' names and units.
void DelimitedReader::read_header() {
  split(content_.front().text);
  have_header_ = o_.header ? *o_.header
                           : !std::all_of(fields_.begin(), fields_.end(), [&](auto f) { return is_number(f); });
  for (std::size_t i = 0; i < fields_.size(); ++i)
    cols_.push_back(have_header_ ? describe_column(fields_[i]) : ColumnName{fmt::format("{}", i + 1), "", ""});
  first_data_ = have_header_ ? 1 : 0;
  const bool scope = have_header_ && content_.size() > 1 && read_scope_header();
  if (!scope && have_header_ && content_.size() > 1) {
    split(content_[1].text);
    std::vector<std::string> units;
    for (const auto f : fields_) units.push_back(unit_cell(f));
    const bool units_row = std::none_of(fields_.begin(), fields_.end(), [&](auto f) { return is_number(f); }) &&
                           std::any_of(units.begin(), units.end(), [](const std::string& u) { return !u.empty(); }) &&
                           std::all_of(fields_.begin(), fields_.end(), [&](std::string_view f) {
                             return f.empty() || !unit_cell(f).empty();
                           });
    if (units_row) {
      for (std::size_t i = 0; i < cols_.size() && i < units.size(); ++i)
        if (cols_[i].unit.empty() && !units[i].empty()) cols_[i].unit = units[i];
      first_data_ = 2;
      unit_rows_ = 1;
    }
  }
  // Names and units go into messages (and JSON): bytes that are not UTF-8 (a header in a legacy
  // encoding read raw) are written \xNN there, once, here.
  for (ColumnName& c : cols_) {
    c.name = text::escape_invalid_utf8(c.name);
    c.unit = text::escape_invalid_utf8(c.unit);
  }
}

// An oscilloscope's "Save CSV" (Rigol's and others'): "X,CH1,Start,Increment," over
// "Sequence,Volt,-4.000000e+00,2.000000e-02": the first column numbers the samples, and sample k
// is at Start + k·Increment seconds. The second row names the units; the rows follow it.
bool DelimitedReader::read_scope_header() {
  int start = -1, increment = -1;
  for (std::size_t i = 0; i < cols_.size(); ++i) {
    const std::string n = ascii_lower(cols_[i].name);
    if (n == "start") start = static_cast<int>(i);
    if (n == "increment") increment = static_cast<int>(i);
  }
  if (start < 0 || increment < 0 || o_.period_ms || !o_.time_column.empty()) return false;
  split(content_[1].text);
  double t0 = 0, dt = 0;
  std::string_view w;
  if (fields_.size() <= static_cast<std::size_t>(std::max(start, increment)) ||
      !parse_number(fields_[static_cast<std::size_t>(start)], decimal_comma_, t0, w) ||
      !parse_number(fields_[static_cast<std::size_t>(increment)], decimal_comma_, dt, w) || !(dt > 0))
    return false;
  if (fields_.size() > 1 && cols_.size() > 1 && cols_[1].unit.empty()) cols_[1].unit = std::string(trim(fields_[1]));
  scope_ = ScopeTiming{t0, dt};
  first_data_ = 2;
  unit_rows_ = 1;
  rec_.note(content_[1].number, fmt::format("an oscilloscope's CSV: sample k of column 1 is at {:g} s + k x {:g} s "
                                            "(its Start and Increment)",
                                            t0, dt));
  return true;
}

// What the numbers say when the names do not: the table's first rows, column by column.
const ColumnGuess& DelimitedReader::guess() {
  if (!guessed_) {
    constexpr std::size_t max_rows = 100'000;
    std::vector<std::vector<double>> table(cols_.size());
    for (std::size_t i = first_data_; i < content_.size() && i - first_data_ < max_rows; ++i) {
      split(content_[i].text);
      for (std::size_t c = 0; c < cols_.size(); ++c) {
        double x = std::numeric_limits<double>::quiet_NaN();
        std::string_view w;
        if (c >= fields_.size() || !parse_number(fields_[c], decimal_comma_, x, w))
          x = std::numeric_limits<double>::quiet_NaN();
        table[c].push_back(x);
      }
    }
    guessed_ = guess_columns(table);
  }
  return *guessed_;
}

// The time and value columns: as named, else by their header names, else the two of a two-column
// file; else the reason, with what the numbers propose.
std::optional<std::string> DelimitedReader::choose_columns() {
  if (cols_.size() < 2 && !o_.period_ms)
    return fmt::format("no samples: line {} has {} field (delimiter {}); need a time and a value column, or the "
                       "readings' period if the sketch printed them at a known rate (--period-ms 20 for delay(20))",
                       content_.front().number, cols_.size(), delim_name_);
  std::string why;
  if (!o_.time_column.empty() && (tcol_ = resolve_named(o_.time_column, cols_, have_header_, &why)) < 0)
    return "time column: " + why;
  if (!o_.value_column.empty() && (vcol_ = resolve_named(o_.value_column, cols_, have_header_, &why)) < 0)
    return "value column: " + why;
  if (tcol_ >= 0 && tcol_ == vcol_) return fmt::format("time and value are both column {}", tcol_ + 1);
  if (o_.period_ms) {  // no time column: the value is the named one, the only one, or the one named a value
    if (vcol_ < 0 && cols_.size() == 1) vcol_ = 0;
    if (vcol_ < 0 && guess().time_counter && guess().value >= 0) vcol_ = guess().value;  // beside a sample number
    if (vcol_ < 0) {
      std::vector<int> named;
      for (std::size_t i = 0; i < cols_.size(); ++i)
        if (is_value_name(cols_[i])) named.push_back(static_cast<int>(i));
      if (named.size() != 1)
        return fmt::format("which of the {} columns ({}) is the value? name it (value column)", cols_.size(),
                           list_columns(cols_));
      vcol_ = named[0];
    }
    tcol_ = vcol_;  // read_rows gives each row its time from the period
    return std::nullopt;
  }
  auto candidates = [&](auto pred, int exclude) {
    std::vector<int> out;
    for (std::size_t i = 0; i < cols_.size(); ++i)
      if (static_cast<int>(i) != exclude && pred(cols_[i])) out.push_back(static_cast<int>(i));
    return out;
  };
  auto names_of = [&](const std::vector<int>& idx) {
    std::string out;
    for (std::size_t k = 0; k < idx.size(); ++k) out += fmt::format("{}'{}'", k ? " and " : "", cols_[idx[k]].name);
    return out;
  };
  const std::string unnamed = have_header_ ? "" : " (the file has no header row)";
  if (tcol_ < 0) {
    auto c = candidates([](const ColumnName& col) { return is_time_name(col); }, vcol_);
    if (c.size() == 1) tcol_ = c[0];
    else if (c.size() > 1) return fmt::format("columns {} could each be the time; name one (time column)", names_of(c));
    else if (scope_) {
      tcol_ = 0;  // the scope's sample number, timed by its Start and Increment
    } else if (cols_.size() == 2) {
      tcol_ = vcol_ == 0 ? 1 : 0;
      if (guess().time_counter && guess().time == tcol_)
        if (const auto p = full_proposal()) return fmt::format("no clock in the file{}: {}", unnamed, *p);
      // Two unnamed columns the other way round (volts<TAB>millis): the numbers say the time is the
      // other one. Refused with the options that read it, never fitted from the wrong column.
      if (!have_header_ && vcol_ < 0 && guess().time == 1)
        if (const auto p = full_proposal())
          return fmt::format("column 1 is no time (it does not rise steadily) but column 2 does: the columns are not "
                             "time, value in that order{}: {}",
                             unnamed, *p);
    } else if (const auto p = full_proposal())
      return fmt::format("cannot tell which of the {} columns is the time{}: {}", cols_.size(), unnamed, *p);
    else
      return fmt::format("cannot tell which of the {} columns is the time{} ({}); name it (time column)", cols_.size(),
                         unnamed, list_columns(cols_));
  }
  if (vcol_ < 0 && scope_ && cols_.size() >= 2) vcol_ = 1;  // CH1
  if (vcol_ < 0) {
    auto c = candidates([](const ColumnName& col) { return is_value_name(col); }, tcol_);
    if (c.size() == 1) vcol_ = c[0];
    else if (c.size() > 1)
      return fmt::format("columns {} could each be the value; name one (value column){}", names_of(c), proposal());
    else if (cols_.size() == 2) vcol_ = tcol_ == 0 ? 1 : 0;
    else if (const auto p = full_proposal(); p && guess().time == tcol_)
      return fmt::format("cannot tell which of the {} columns is the value{}: {}", cols_.size(), unnamed, *p);
    else
      return fmt::format("cannot tell which of the {} columns is the value{} ({}); name it (value column)",
                         cols_.size(), unnamed, list_columns(cols_));
  }
  return std::nullopt;
}

// The quantity and the factor that turns a reading into it (mV: 0.001 V): as given, else from the
// value column's header, else volts when there is no header; and a time unit spindown reads.
std::optional<std::string> DelimitedReader::choose_value_unit() {
  const ColumnName& value_col = cols_[vcol_];
  if (o_.quantity) {
    rec_.quantity = *o_.quantity;
    value_scale_ = o_.value_scale;
  } else if (auto u = implied_value_unit(value_col)) {
    rec_.quantity = u->quantity;
    value_scale_ = u->scale;
    value_unit_name_ = u->name;
    quantity_from_ = "from the header";
  } else if (!have_header_) {
    rec_.quantity = Quantity::back_emf_volts;
    quantity_from_ = "assumed: no header";
  } else {
    const std::string_view likely = likely_value_unit(value_col);
    const std::string option =
        likely.empty() ? std::string("--value-unit V, rpm or rad/s") : fmt::format("--value-unit {}", likely);
    if (unknown_value_unit(value_col))
      return fmt::format("value column '{}': its unit '{}' is not one spindown reads ({}); if the readings are one "
                         "of those under another name, say which: {}",
                         value_col.name, value_col.unit, value_units_read(), option);
    return fmt::format("cannot tell the unit of value column '{}' (V, rpm or rad/s); name it: {}", value_col.name,
                       option);
  }
  if (!o_.period_ms && !o_.time_unit && !cols_[tcol_].unit.empty() && !parse_time_unit(cols_[tcol_].unit))
    return fmt::format("time column '{}': its unit '{}' is not one spindown reads (s, ms, us); convert the times or "
                       "name their unit: --time-unit s, ms or us",
                       cols_[tcol_].name, cols_[tcol_].unit);
  return std::nullopt;
}

// Each row's time and value (DelimitedRowReader, by the layout chosen); a row without them is said
// (the first few one by one) and skipped.
void DelimitedReader::read_rows() {
  reporter_.emplace(rec_, o_.max_line_reports);
  raw_.reserve(content_.size());
  DelimitedLayout layout;
  layout.delimiter = delim_;
  layout.decimal_comma = decimal_comma_;
  layout.time_column = tcol_;
  layout.value_column = vcol_;
  layout.quantity = rec_.quantity;
  layout.quantity_from_header = quantity_from_ == "from the header";
  layout.value_scale = value_scale_;
  rows_ = DelimitedRowReader(layout);
  for (std::size_t i = first_data_; i < content_.size(); ++i) {
    const Line& line = content_[i];
    const DelimitedRowReader::Row row = rows_.read(line.text);
    if (!row.ok) {
      if (auto name = text::written_name(line.text)) {
        rec_.names.push_back({raw_.size(), *name, line.number});
        rec_.note(line.number, fmt::format("{}: a name written between the samples: the runs after it are {}'s",
                                           text::quote_line(line.text), *name));
        continue;
      }
      ++bad_;
      reporter_->warn(line.number, fmt::format("{}: {}; skipped", text::quote_line(line.text), row.why));
      continue;
    }
    const double t = o_.period_ms ? *o_.period_ms * double(raw_.size())
                     : scope_     ? scope_->start_s + row.time * scope_->increment_s
                                  : row.time;
    raw_.add(line.number, line.text.data(), t, row.value, false);
  }
}

// The time unit (given, from the header, else from the values, said), the timeline, and the
// summary of what was read.
void DelimitedReader::choose_time_unit_and_finish() {
  TimeUnit unit = TimeUnit::s;
  std::string unit_from = "given";
  if (o_.period_ms) {
    unit = TimeUnit::ms;
    unit_from = fmt::format("a reading every {:g} ms", *o_.period_ms);
  } else if (scope_) {
    unit = TimeUnit::s;
    unit_from = fmt::format("the scope's Start {:g} s and Increment {:g} s", scope_->start_s, scope_->increment_s);
  } else if (o_.time_unit) {
    unit = *o_.time_unit;
  } else if (auto u = implied_time_unit(cols_[tcol_])) {
    unit = *u;
    unit_from = "from the header";
  } else {
    bool integral = false;
    double step = 0;
    unit = time_unit_from_values(std::span<const double>(raw_.t.data(), std::min<std::size_t>(raw_.size(), 65)),
                                 &integral, &step);
    unit_from = "assumed";
    rec_.note(0, fmt::format("time unit not given: times {} with steps of ~{:g}, read as {}; name the unit if that "
                             "is wrong",
                             integral ? "are whole numbers" : "have fractions", step, time_unit_name(unit)));
  }

  rows_.set_time_unit(unit);
  text::TimelineRules rules;
  rules.units_per_s = time_units_per_second(unit);
  rules.unit = time_unit_name(unit);
  // Whole ms or µs are a microcontroller's millis() or micros(): a 32-bit counter that wraps at 2^32
  // (micros() every 71.6 min). A PC logger's times (fractions, seconds) do not wrap.
  bool whole = !o_.period_ms && !scope_ && (unit == TimeUnit::ms || unit == TimeUnit::us) && raw_.size() > 0;
  for (std::size_t i = 0; whole && i < std::min<std::size_t>(raw_.size(), 200); ++i) whole = raw_.t[i] == std::floor(raw_.t[i]);
  rules.wrap = whole ? 4294967296.0 : 0;
  rules.reset_min_back = rules.units_per_s;
  rules.drop_cut_first = false;
  const text::TimelineCounts timeline = text::build_timeline(raw_, rules, rec_, *reporter_);
  reporter_->finish();
  text::sort_by_line(rec_);
  rec_.lines_skipped = rec_.lines_read - rec_.size();

  const std::string value_unit =
      value_scale_ != 1 && !value_unit_name_.empty()
          ? fmt::format("{} read as {}", value_unit_name_, quantity_unit(rec_.quantity))
          : value_scale_ != 1 ? fmt::format("{} x {:g}", quantity_unit(rec_.quantity), value_scale_)
                              : std::string(quantity_unit(rec_.quantity));
  const std::string time = o_.period_ms ? fmt::format("time = {} (--period-ms)", unit_from)
                                        : fmt::format("time = column {} '{}' in {} ({})", tcol_ + 1, cols_[tcol_].name,
                                                      time_unit_name(unit), unit_from);
  const std::string columns = fmt::format("{}, value = column {} '{}' in {} ({}), delimiter {}", time, vcol_ + 1,
                                          cols_[vcol_].name, value_unit, quantity_from_, delim_name_);
  if (rec_.empty()) {
    rec_.error(0, fmt::format("no samples: {} lines, none with a usable time and value ({})", lines_, columns));
    return;
  }
  rec_.note(0, text::summary_with_counts(fmt::format("{} samples from {} lines; {}", rec_.size(), lines_, columns),
                                         {{have_header_ ? 1u : 0u, "header row"},
                                          {unit_rows_, "units row"},
                                          {headers_, "PuTTY header"},
                                          {comments_, "comment"},
                                          {blank_, "blank"},
                                          {bad_, "unusable"}},
                                         timeline));
}

}  // namespace

Recording read_delimited_text(std::string_view text, std::string source, const DelimitedTextOptions& options,
                              DelimitedLayout* layout) {
  Recording rec;
  rec.source = std::move(source);
  if (!text::readable_text(text, options, "delimited text", rec)) return rec;
  DelimitedReader reader(text, options, rec);
  const auto give_up = [&](std::string message) {
    rec.error(0, std::move(message));
    rec.lines_skipped = rec.lines_read;
    return rec;
  };
  reader.collect_lines();
  if (reader.empty()) return give_up(reader.nothing_in_it());
  reader.choose_delimiter();
  reader.skip_cut_first_line();
  reader.read_header();
  if (auto why = reader.choose_columns()) return give_up(std::move(*why));
  if (auto why = reader.choose_value_unit()) return give_up(std::move(*why));
  reader.read_rows();
  reader.choose_time_unit_and_finish();
  if (layout) *layout = reader.layout();
  return rec;
}

Recording read_delimited_text_file(const std::string& path, const DelimitedTextOptions& options) {
  return text::read_text_file(path, options, [](std::string_view bytes, const std::string& source, const auto& o) {
    return read_delimited_text(bytes, source, o);
  });
}

}  // namespace spindown
