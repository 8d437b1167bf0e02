#include "spindown/csv_fields.hpp"

#include <algorithm>

namespace spindown {

namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }

// Blanks around a field, except the delimiter itself (a tab in TSV).
std::string_view trim_blanks(std::string_view s, char delimiter) {
  auto blank = [delimiter](char c) { return is_blank(c) && c != delimiter; };
  while (!s.empty() && blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && blank(s.back())) s.remove_suffix(1);
  return s;
}

}  // namespace

void CsvFieldSplitter::split(std::string_view line, char delimiter, std::vector<std::string_view>& out) {
  out.clear();
  open_quote_ = false;
  const bool blanks = delimiter == ' ';
  const bool quotes = line.find('"') != std::string_view::npos;
  // Every byte a quoted field keeps comes from a byte of the line: with this room no append
  // reallocates, so the views handed out stay valid.
  if (quotes) {
    unquoted_.clear();
    unquoted_.reserve(line.size());
  }
  const auto is_delimiter = [&](char c) { return blanks ? is_blank(c) : c == delimiter; };
  const auto next_delimiter = [&](std::size_t from) {
    if (!blanks) return std::min(line.find(delimiter, from), line.size());
    while (from < line.size() && !is_blank(line[from])) ++from;
    return from;
  };
  std::size_t i = 0;
  if (blanks) {
    while (i < line.size() && is_blank(line[i])) ++i;
    if (i == line.size()) return;
  }
  for (;;) {
    // One field from i: up to the next delimiter outside quotes.
    std::size_t j = i;
    while (j < line.size() && is_blank(line[j]) && !is_delimiter(line[j])) ++j;
    if (quotes && j < line.size() && line[j] == '"') {
      const std::size_t start = unquoted_.size();
      ++j;
      for (;;) {
        const std::size_t q = line.find('"', j);
        if (q == std::string_view::npos) {  // never closed: the rest of the line
          unquoted_.append(line.substr(j));
          j = line.size();
          open_quote_ = true;
          break;
        }
        unquoted_.append(line.substr(j, q - j));
        if (q + 1 < line.size() && line[q + 1] == '"') {  // "" is a quote
          unquoted_ += '"';
          j = q + 2;
          continue;
        }
        j = q + 1;
        break;
      }
      // Text after the closing quote (not RFC 4180, but spreadsheets keep it): part of the field.
      const std::size_t k = next_delimiter(j);
      unquoted_.append(trim_blanks(line.substr(j, k - j), delimiter));
      out.emplace_back(unquoted_.data() + start, unquoted_.size() - start);
      i = k;
    } else {
      const std::size_t k = next_delimiter(i);
      out.push_back(trim_blanks(line.substr(i, k - i), delimiter));
      i = k;
    }
    if (i >= line.size()) return;
    ++i;  // past the delimiter
    if (blanks) {
      while (i < line.size() && is_blank(line[i])) ++i;
      if (i == line.size()) return;  // trailing blanks end the line, no empty field
    } else if (i == line.size()) {
      out.emplace_back();  // "a,b," has an empty last field
      return;
    }
  }
}

}  // namespace spindown
