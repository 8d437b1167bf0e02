#pragma once
// A JSON writer laid out exactly as nlohmann's dump(2, ' ', false, error_handler_t::replace), or
// compact as dump(-1, …), straight into a string: the one writer of the `fit --json` contract
// (fit_json.cpp). Private to the report module.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

inline constexpr bool is_plain_char(unsigned char c) { return c >= 0x20 && c <= 0x7E && c != '"' && c != '\\'; }

// Printable ASCII without '"' or '\\': a JSON string of it is the text in quotes. Sixteen bytes
// at a time with GCC's vector extension (the long values: reasons, sources, messages).
inline bool is_plain(std::string_view s) {
  using Bytes = unsigned char __attribute__((vector_size(16)));
  const auto* p = reinterpret_cast<const unsigned char*>(s.data());
  const std::size_t n = s.size();
  std::size_t i = 0;
  for (; n - i >= sizeof(Bytes); i += sizeof(Bytes)) {
    Bytes b;
    std::memcpy(&b, p + i, sizeof b);
    const auto escaped = (b < 0x20) | (b > 0x7E) | (b == '"') | (b == '\\');
    std::uint64_t lanes[2];
    std::memcpy(lanes, &escaped, sizeof lanes);
    if ((lanes[0] | lanes[1]) != 0) return false;
  }
  for (; i < n; ++i)
    if (!is_plain_char(p[i])) return false;
  return true;
}

// A member name written in the source: checked when compiling to need no escape, so the writer
// copies it as it is.
class PlainKey {
 public:
  template <std::size_t N>
  consteval PlainKey(const char (&text)[N]) : text_(text, N - 1) {  // NOLINT: implicit on purpose
    for (char c : text_)
      if (!is_plain_char(static_cast<unsigned char>(c))) throw "a PlainKey is printable ASCII without '\"' or '\\'";
  }
  std::string_view text() const { return text_; }

 private:
  std::string_view text_;
};

// Writes JSON laid out as nlohmann's dump(2, ' ', false, error_handler_t::replace): "{" then each
// member on its own line indented two more, "key": value, ",\n" between members, the closing
// bracket on its own line at the container's indent; "{}" and "[]" when empty. Compact, as
// dump(-1, …): no line breaks or indent, "key":value, "," between members.
//
// The text goes straight into out's bytes through a cursor (room made ahead, doubling; out is cut
// to what was written when the writer goes): a member is a few small copies, where
// std::string's appends cost more than the bytes (a file's JSON is ~60 members).
class JsonWriter {
 public:
  JsonWriter(std::string& out, std::size_t indent, bool compact = false)
      : out_(out), size_(out.size()), indent_(indent), compact_(compact) {
    out_.resize(std::max(out_.capacity(), size_ + 256));
  }
  ~JsonWriter() { out_.resize(size_); }
  JsonWriter(const JsonWriter&) = delete;
  JsonWriter& operator=(const JsonWriter&) = delete;

  void begin_object() { open('{'); }
  void end_object() { close('}'); }
  void begin_array() { open('['); }
  void end_array() { close(']'); }

  // A member's key; its value follows.
  void key(PlainKey k) {
    next_element();
    quoted_key(k.text());
  }
  // A key only known at run time (a parameter's name): escaped when it needs it.
  void runtime_key(std::string_view k) {
    next_element();
    if (!is_plain(k)) {
      string(k);
      put(compact_ ? ":" : ": ");
      return;
    }
    quoted_key(k);
  }
  // An array element's start; its value follows.
  void element() { next_element(); }

  void string(std::string_view s) {
    if (is_plain(s)) {
      char* p = room(s.size() + 2);
      *p++ = '"';
      std::memcpy(p, s.data(), s.size());
      p[s.size()] = '"';
      size_ += s.size() + 2;
    } else {  // escapes and bytes that are not UTF-8: nlohmann's own serializer, exactly
      put(nlohmann::ordered_json(s).dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace));
    }
  }
  void number(double x) {  // JSON has no inf/NaN: a stop that never comes or an undefined R² is null
    if (!std::isfinite(x)) {
      put("null");
      return;
    }
    // The shortest digits that read back as x: what dump() writes for a double (the same
    // function), without building a Json and a string per number.
    constexpr std::size_t most = 64;  // to_chars needs max_digits10 + a sign, point and exponent
    char* p = room(most);
    size_ += static_cast<std::size_t>(nlohmann::detail::to_chars(p, p + most, x) - p);
  }
  void integer(std::int64_t n) { put(std::string_view(fmt::format_int(n).c_str())); }
  void unsigned_integer(std::size_t n) { put(std::string_view(fmt::format_int(n).c_str())); }
  void boolean(bool b) { put(b ? std::string_view("true") : std::string_view("false")); }
  void null() { put("null"); }

  // Shorthands for a member and its value.
  void member(PlainKey k, std::string_view v) {
    key(k);
    string(v);
  }
  void member(PlainKey k, const char* v) { member(k, std::string_view(v)); }
  void member_number(PlainKey k, double x) {
    key(k);
    number(x);
  }
  void member(PlainKey k, bool b) {
    key(k);
    boolean(b);
  }

 private:
  // ",\n" and the spaces of the deepest indent the documents use, so a member's line break and
  // indent are one copy.
  static constexpr std::size_t layout_spaces = 126;
  static constexpr std::array<char, 2 + layout_spaces> layout = [] {
    std::array<char, 2 + layout_spaces> a{};
    a[0] = ',';
    a[1] = '\n';
    for (std::size_t i = 2; i < a.size(); ++i) a[i] = ' ';
    return a;
  }();

  // Room for n more bytes at the cursor.
  char* room(std::size_t n) {
    if (out_.size() - size_ < n) out_.resize(std::max(2 * out_.size(), size_ + n));
    return out_.data() + size_;
  }
  void put(std::string_view s) {
    std::memcpy(room(s.size()), s.data(), s.size());
    size_ += s.size();
  }
  void quoted_key(std::string_view k) {  // "k": , k needing no escape
    char* p = room(k.size() + 4);
    *p++ = '"';
    std::memcpy(p, k.data(), k.size());
    std::memcpy(p + k.size(), "\": ", 3);
    size_ += k.size() + (compact_ ? 3 : 4);
  }
  // A line break, then the indent (compact: only the comma).
  void new_line(bool comma) {
    if (compact_) {
      if (comma) put(",");
      return;
    }
    if (indent_ > layout_spaces) {  // deeper than any document here: not worth a faster way
      put(comma ? ",\n" : "\n");
      put(std::string(indent_, ' '));
      return;
    }
    const std::size_t skip = comma ? 0 : 1, n = 2 - skip + indent_;
    std::memcpy(room(n), layout.data() + skip, n);
    size_ += n;
  }

  void open(char bracket) {
    put(std::string_view(&bracket, 1));
    empty_.push_back(true);
    indent_ += 2;
  }
  void close(char bracket) {
    indent_ -= 2;
    if (!empty_.back()) new_line(false);
    empty_.pop_back();
    put(std::string_view(&bracket, 1));
  }
  void next_element() {
    new_line(!empty_.back());
    empty_.back() = false;
  }

  std::string& out_;
  std::size_t size_;  // bytes of out_ written; the rest is room
  std::size_t indent_;
  bool compact_;
  std::vector<bool> empty_;  // per open container: nothing written in it yet
};

}  // namespace spindown
