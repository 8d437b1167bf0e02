#include "spindown/text_repairs.hpp"

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fmt/format.h>

#include "spindown/text_encoding.hpp"
#include "spindown/text_support.hpp"

namespace spindown {

namespace {

constexpr std::size_t head_bytes = 8192;  // what the checks look at
constexpr bool is_digit(char c) { return c >= '0' && c <= '9'; }

// "10:21:38.234 -> ": the Arduino IDE serial monitor's "Show timestamp". Its length, or 0.
std::size_t timestamp_prefix(std::string_view line) {
  constexpr std::string_view shape = "00:00:00.000 -> ";
  if (line.size() < shape.size()) return 0;
  for (std::size_t i = 0; i < shape.size(); ++i) {
    if (shape[i] == '0' ? !is_digit(line[i]) : line[i] != shape[i]) return 0;
  }
  return shape.size();
}

// The timestamp's time of day in ms ("10:21:38.234" → 37,298,234); line starts with one.
std::int64_t timestamp_ms(std::string_view line) {
  auto num = [&](std::size_t at, std::size_t n) {
    std::int64_t v = 0;
    for (std::size_t i = at; i < at + n; ++i) v = v * 10 + (line[i] - '0');
    return v;
  };
  return ((num(0, 2) * 60 + num(3, 2)) * 60 + num(6, 2)) * 1000 + num(9, 3);
}

// What follows a timestamp is one number alone ("2.64": a sketch that prints only the volts).
bool one_number(std::string_view rest) {
  while (!rest.empty() && (rest.back() == '\r' || rest.back() == ' ')) rest.remove_suffix(1);
  if (rest.empty()) return false;
  std::size_t i = rest[0] == '-' ? 1 : 0, digits = 0;
  for (; i < rest.size(); ++i) {
    if (is_digit(rest[i])) ++digits;
    else if (rest[i] != '.') return false;
  }
  return digits > 0;
}

// A line of the lab's two columns whose value has a decimal comma: "<digits><TAB|spaces>[-]
// <digits>,<digits>" and trailing space or CR. Sets *comma to the comma's offset.
bool comma_sample(std::string_view line, std::size_t* comma) {
  std::size_t i = 0;
  while (i < line.size() && line[i] == ' ') ++i;
  const std::size_t t0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == t0 || i == line.size() || (line[i] != '\t' && line[i] != ' ')) return false;
  while (i < line.size() && (line[i] == '\t' || line[i] == ' ')) ++i;
  if (i < line.size() && line[i] == '-') ++i;
  const std::size_t v0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == v0 || i == line.size() || line[i] != ',') return false;
  *comma = i++;
  const std::size_t f0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == f0) return false;
  while (i < line.size() && (line[i] == ' ' || line[i] == '\r')) ++i;
  return i == line.size();
}

// The same line with a decimal point: "5234\t2.45".
bool point_sample(std::string_view line) {
  std::size_t i = 0;
  while (i < line.size() && is_digit(line[i])) ++i;
  if (i == 0 || i == line.size() || (line[i] != '\t' && line[i] != ' ')) return false;
  while (i < line.size() && (line[i] == '\t' || line[i] == ' ')) ++i;
  if (i < line.size() && line[i] == '-') ++i;
  const std::size_t v0 = i;
  while (i < line.size() && is_digit(line[i])) ++i;
  return i > v0 && i < line.size() && line[i] == '.';
}

template <class F>
void each_line(std::string_view text, std::size_t limit, F&& f) {
  std::size_t pos = 0;
  while (pos < text.size() && pos < limit) {
    std::size_t nl = text.find('\n', pos);
    if (nl == std::string_view::npos) nl = text.size();
    f(text.substr(pos, nl - pos), pos);
    pos = nl + 1;
  }
}

// A Python bytes literal as print(ser.readline()) writes it: b'5234\t2.80\r\n' (or in double
// quotes). Its content, unescaped, into out; false when line is not one.
bool bytes_literal(std::string_view line, std::string* out) {
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.remove_suffix(1);
  if (line.size() < 3 || line[0] != 'b' || (line[1] != '\'' && line[1] != '"') || line.back() != line[1]) return false;
  const std::string_view body = line.substr(2, line.size() - 3);
  std::string text;
  for (std::size_t i = 0; i < body.size(); ++i) {
    if (body[i] != '\\') {
      text += body[i];
      continue;
    }
    if (++i == body.size()) return false;
    switch (body[i]) {
      case 't': text += '\t'; break;
      case 'r':
      case 'n': break;  // the line's own end: the line ends here anyway
      case '\\': text += '\\'; break;
      case '\'': text += '\''; break;
      case '"': text += '"'; break;
      case 'x': {
        if (i + 2 >= body.size()) return false;
        int v = 0;
        for (const char h : body.substr(i + 1, 2)) {
          const char l = static_cast<char>(h | 0x20);
          const int d = is_digit(h) ? h - '0' : l >= 'a' && l <= 'f' ? l - 'a' + 10 : -1;
          if (d < 0) return false;
          v = v * 16 + d;
        }
        text += static_cast<char>(v);
        i += 2;
        break;
      }
      default: return false;
    }
  }
  if (out) *out = std::move(text);
  return true;
}

// What the head of a text (its first head_bytes) shows, line by line, in one pass: every check of
// whether a text needs repair reads these counts (an ordinary file is read once more, not five times).
struct HeadCounts {
  std::size_t lines = 0, timestamped = 0, value_only = 0, comma = 0, point = 0, bytes_literals = 0, plotter = 0;
};

HeadCounts count_head(std::string_view text) {
  HeadCounts c;
  each_line(text, head_bytes, [&](std::string_view line, std::size_t) {
    if (line.empty() || line == "\r") return;
    ++c.lines;
    c.bytes_literals += bytes_literal(line, nullptr);
    c.plotter += plotter_labels(line, nullptr, nullptr);
    const std::size_t skip = timestamp_prefix(line);
    c.timestamped += skip > 0;
    line.remove_prefix(skip);
    c.value_only += skip > 0 && one_number(line);
    std::size_t comma = 0;
    c.comma += comma_sample(line, &comma);
    c.point += point_sample(line);
  });
  return c;
}

// Each line of text given to f(line, out), which appends its new text to out and returns true,
// or false to keep the line as it is; line ends stay where they were. How many f rewrote.
template <class F>
std::size_t rewrite_lines(std::string& text, F&& f) {
  std::string out;
  out.reserve(text.size());
  std::size_t rewritten = 0;
  each_line(text, text.size(), [&](std::string_view line, std::size_t pos) {
    if (f(line, out)) ++rewritten;
    else out.append(line);
    if (pos + line.size() < text.size()) out += '\n';
  });
  text.swap(out);
  return rewritten;
}

bool plotter_lines_to_unlabel(const HeadCounts& c) { return c.plotter >= 3 && c.plotter * 2 >= c.lines; }
bool bytes_literals_to_unwrap(const HeadCounts& c) { return c.bytes_literals >= 3 && c.bytes_literals * 2 >= c.lines; }

bool timestamps_to_strip(const HeadCounts& c) { return c.timestamped >= 3 && c.timestamped * 2 >= c.lines; }
bool commas_to_read(const HeadCounts& c) { return c.comma >= 5 && c.point == 0; }

}  // namespace

namespace {

// The encoding to undo: none for binary data and office documents, which the readers refuse.
EncodingGuess encoding_to_undo(std::string_view text) {
  EncodingGuess g = guess_text_encoding(text);
  if (!needs_decoding(g)) return g;  // the usual ASCII file: no binary check here (the reader makes it)
  const bool wide = g.encoding == TextEncoding::utf16le || g.encoding == TextEncoding::utf16be;
  if (!wide && (text::looks_binary(text) || office_document(text))) return {};
  return g;
}

}  // namespace

bool plotter_labels(std::string_view line, std::string* labels, std::string* values) {
  if (line.find(':') == std::string_view::npos) return false;  // the usual line, at once
  while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t' || line.back() == ','))
    line.remove_suffix(1);
  if (line.empty()) return false;
  std::string names, nums;
  std::size_t fields = 0, at = 0;
  while (at <= line.size()) {
    std::size_t end = line.find_first_of(",\t ", at);
    if (end == std::string_view::npos) end = line.size();
    const std::string_view f = line.substr(at, end - at);
    if (!f.empty()) {
      const std::size_t colon = f.find(':');
      if (colon == 0 || colon == std::string_view::npos || colon + 1 == f.size()) return false;
      const std::string_view name = f.substr(0, colon), num = f.substr(colon + 1);
      if (name.find_first_of("0123456789.") == 0) return false;  // "10:21:38" is a clock, not a label
      for (const char c : num)
        if (!is_digit(c) && c != '.' && c != '-' && c != '+' && c != 'e' && c != 'E') return false;
      (names += fields ? "," : "") += name;
      (nums += fields ? "," : "") += num;
      ++fields;
    }
    at = end + 1;
  }
  if (fields < 2) return false;
  if (labels) *labels = std::move(names);
  if (values) *values = std::move(nums);
  return true;
}

namespace {

// A LabVIEW Measurement file (.lvm, "Write to Measurement File"): a file header and a channel
// header, each closed by ***End_of_Header***, then a line of column names and the rows. With
// X_Columns No the rows hold the readings alone: their times are X0 + k·Delta_X (the channel
// header's). The headers become blank lines, the names "t_s" and the channels' names with their
// unit (Y_Unit_Label), and each row its time in s before its readings: every line stays where it
// was. Empty: not such a file, or one it cannot read so (a decimal comma, no Delta_X).
std::string lvm_note(std::string& text) {
  if (!text.starts_with("LabVIEW Measurement")) return {};
  std::vector<std::string_view> lines;
  each_line(text, text.size(), [&](std::string_view line, std::size_t) { lines.push_back(line); });
  const auto field = [](std::string_view line, std::size_t k) {  // tab-separated field k, trimmed
    std::size_t at = 0;
    for (std::size_t i = 0; i < k && at != std::string_view::npos; ++i) {
      at = line.find('\t', at);
      if (at != std::string_view::npos) ++at;
    }
    if (at == std::string_view::npos) return std::string_view{};
    std::string_view f = line.substr(at, line.find('\t', at) - at);
    while (!f.empty() && (f.back() == '\r' || f.back() == ' ')) f.remove_suffix(1);
    return f;
  };
  std::size_t ends = 0, names = 0;
  std::string x_columns = "One", decimal = ".", unit;
  double x0 = 0, dx = 0;
  for (std::size_t i = 0; i < lines.size() && ends < 2; ++i) {
    const std::string_view key = field(lines[i], 0), value = field(lines[i], 1);
    if (key.starts_with("***End_of_Header***")) {
      if (++ends == 2) names = i + 1;
    } else if (key == "X_Columns") {
      x_columns = std::string(value);
    } else if (key == "Decimal_Separator") {
      decimal = std::string(value);
    } else if (key == "Delta_X") {
      dx = std::strtod(std::string(value).c_str(), nullptr);
    } else if (key == "X0") {
      x0 = std::strtod(std::string(value).c_str(), nullptr);
    } else if (key == "Y_Unit_Label") {
      unit = std::string(value);
    }
  }
  if (ends < 2 || names >= lines.size() || decimal != ".") return {};
  const bool no_x = x_columns == "No";
  if (no_x && !(dx > 0)) return {};
  const std::string suffix = unit == "Volts" || unit == "V" ? "_V" : unit == "mV" ? "_mV" : unit == "RPM" || unit == "rpm" ? "_rpm" : "";
  std::string out;
  out.reserve(text.size() + 16 * (lines.size() - names));
  for (std::size_t i = 0; i < names; ++i) out += '\n';
  // The column names: X_Value is the time; a trailing Comment column is no reading.
  std::string head = no_x ? "t_s" : "";
  for (std::size_t k = 0;; ++k) {
    std::string_view f = field(lines[names], k);
    if (f.empty() && k > 0) break;
    if (f == "Comment") break;
    if (!head.empty()) head += '\t';
    head += f == "X_Value" ? std::string("t_s") : std::string(f) + (f.empty() ? "value" : "") + suffix;
  }
  out += head;
  std::size_t rows = 0;
  for (std::size_t i = names + 1; i < lines.size(); ++i) {
    out += '\n';
    std::string_view row = lines[i];
    while (!row.empty() && (row.back() == '\r' || row.back() == '\t' || row.back() == ' ')) row.remove_suffix(1);
    if (row.empty()) continue;
    if (no_x) out += fmt::format("{:.9g}\t", x0 + double(rows) * dx);
    out.append(row);
    ++rows;
  }
  if (!text.empty() && text.back() == '\n') out += '\n';
  text.swap(out);
  return no_x ? fmt::format("a LabVIEW measurement file (.lvm) without a time column: each reading's time from its "
                            "header, X0 {:g} s + k × Delta_X {:g} s ({} rows)",
                            x0, dx, rows)
              : fmt::format("a LabVIEW measurement file (.lvm): its headers skipped, X_Value read as the time in s ({} rows)",
                            rows);
}

}  // namespace

bool needs_text_repair(std::string_view text) {
  if (text.starts_with("LabVIEW Measurement")) return true;
  if (needs_decoding(encoding_to_undo(text))) return true;
  // Each repair needs at least three lines of its kind in the head (five for the decimal commas),
  // each with a ':' (a timestamp, a plotter's label), a ',' or a quote (a bytes literal): a head
  // with fewer of those characters needs none, known without reading it line by line.
  const std::string_view head = text.substr(0, text.size() > head_bytes ? text.find('\n', head_bytes) : text.size());
  const auto has = [&](char ch, std::size_t n) {  // memchr's pace: most heads have none at all
    for (std::size_t at = head.find(ch); at != std::string_view::npos; at = head.find(ch, at + 1))
      if (--n == 0) return true;
    return false;
  };
  if (!has(':', 3) && !has(',', 5) && !has('\'', 3) && !has('"', 3)) return false;
  const HeadCounts c = count_head(text);
  return bytes_literals_to_unwrap(c) || plotter_lines_to_unlabel(c) || timestamps_to_strip(c) || commas_to_read(c);
}

std::vector<std::string> repair_text(std::string& text) {
  std::vector<std::string> notes;
  if (const EncodingGuess g = encoding_to_undo(text); needs_decoding(g)) {
    text = decode_text(text, g);
    if (std::string note = decoding_note(g); !note.empty()) notes.push_back(std::move(note));
  }
  if (std::string note = lvm_note(text); !note.empty()) notes.push_back(std::move(note));  // once decoded
  if (bytes_literals_to_unwrap(count_head(text))) {
    std::string content;
    const std::size_t unwrapped = rewrite_lines(text, [&](std::string_view line, std::string& out) {
      if (!bytes_literal(line, &content)) return false;
      out += content;
      return true;
    });
    notes.push_back(fmt::format("Python bytes literals (b'5234\\t2.80\\r\\n', as print(ser.readline()) of a pyserial "
                                "script writes them) unwrapped in {} lines",
                                unwrapped));
  }
  if (plotter_lines_to_unlabel(count_head(text))) {
    std::string labels, values, header;
    const std::size_t unlabelled = rewrite_lines(text, [&](std::string_view line, std::string& out) {
      if (!plotter_labels(line, &labels, &values)) return false;
      if (header.empty()) {  // the labels once, as the header the values are read under
        header = labels;
        out += header + '\n';
      }
      out += values;
      return true;
    });
    notes.push_back(fmt::format("the Serial Plotter's labelled values (\"{}:…\") in {} lines: read as a table with "
                                "columns {} (its header put above them: later line numbers count one more than the "
                                "file's)",
                                header.substr(0, header.find(',')), unlabelled, header));
  }
  const HeadCounts c = count_head(text);
  const bool strip = timestamps_to_strip(c), commas = commas_to_read(c);
  if (!strip && !commas) return notes;
  // A sketch that prints the volts alone: the timestamp (the PC's time of arrival) is the only
  // time there is, so it becomes the time column, in ms of the day (across midnight: on).
  const bool as_time = strip && c.value_only * 5 >= c.timestamped * 4;
  std::int64_t last_ms = -1, days = 0;
  std::string out;
  out.reserve(text.size());
  std::size_t stripped = 0, converted = 0;
  each_line(text, text.size(), [&](std::string_view line, std::size_t pos) {
    const bool newline = pos + line.size() < text.size();  // the line ended in '\n'
    if (strip) {
      const std::size_t skip = timestamp_prefix(line);
      stripped += skip > 0;
      if (skip > 0 && as_time) {
        const std::int64_t ms = timestamp_ms(line);
        if (last_ms >= 0 && ms + 12 * 3600 * 1000 < last_ms) ++days;  // past midnight
        last_ms = ms;
        out += std::to_string(ms + days * 86'400'000) + '\t';
      }
      line.remove_prefix(skip);
    }
    std::size_t comma = 0;
    if (commas && comma_sample(line, &comma)) {
      out.append(line.substr(0, comma));
      out += '.';
      out.append(line.substr(comma + 1));
      ++converted;
    } else {
      out.append(line);
    }
    if (newline) out += '\n';
  });
  text.swap(out);
  if (strip && as_time)
    notes.push_back(fmt::format("Arduino IDE serial monitor timestamps (\"10:21:38.234 -> \") on {} lines of one value "
                                "each: the timestamp, when the PC received the line, is its time (ms of the day; "
                                "USB delivers lines in bursts, so times are only as good as a few ms)",
                                stripped));
  else if (strip)
    notes.push_back(fmt::format("Arduino IDE serial monitor timestamps (\"10:21:38.234 -> \") removed from {} lines; "
                                "each sample's own millis is its time",
                                stripped));
  if (commas)
    notes.push_back(fmt::format("decimal commas read as points in {} lines (\"2,45\" is 2.45)", converted));
  return notes;
}

}  // namespace spindown
