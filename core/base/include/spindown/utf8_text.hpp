#pragma once
// Widths and cuts of UTF-8 text in code points, the columns a terminal gives text of one-column
// characters ("±", "·", "²" take one, however many bytes): for tables and legends that must fit a
// width, and cut text never inside a character.
#include <cstddef>
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
