#pragma once
// UTF-8 text: widths and cuts in code points, the columns a terminal gives text of one-column
// characters ("±", "·", "²" take one, however many bytes), for tables and legends that must fit a
// width and cut text never inside a character; and text that came from outside (a file's bytes, a
// host name in a received LCM message) shown so that what is printed stays valid UTF-8, which
// JSON and terminals need.
#include <cstddef>
#include <string>
#include <string_view>

namespace spindown {

// Code points of a UTF-8 string.
inline std::size_t display_width(std::string_view utf8) {
  std::size_t n = 0;
  for (unsigned char c : utf8)
    if ((c & 0xC0) != 0x80) ++n;
  return n;
}

// Bytes of the first n code points of utf8 (all of it when it has fewer).
inline std::size_t utf8_prefix_bytes(std::string_view utf8, std::size_t n) {
  std::size_t points = 0;
  for (std::size_t i = 0; i < utf8.size(); ++i) {
    if ((static_cast<unsigned char>(utf8[i]) & 0xC0) == 0x80) continue;
    if (points == n) return i;
    ++points;
  }
  return utf8.size();
}

}  // namespace spindown

namespace spindown::text {

// Length of the valid UTF-8 sequence starting at s[i] (1 to 4); 0 when none starts there.
std::size_t utf8_sequence_length(std::string_view s, std::size_t i);
// s unquoted and uncut, every byte that is not part of valid UTF-8 written as \xNN.
std::string escape_invalid_utf8(std::string_view s);

}  // namespace spindown::text
