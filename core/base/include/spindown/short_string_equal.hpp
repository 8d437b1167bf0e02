#pragma once
// Equality of two short strings (channel names, bench ids: a few to a few dozen bytes) compared
// eight bytes at a time in registers (four for names of 4 to 7 bytes, such as "lab1"). A
// per-message name check costs a handful of instructions instead of a call into memcmp, which
// dominates it at one sample per message.
#include <cstdint>
#include <cstring>
#include <string_view>

namespace spindown {

inline bool short_string_equal(std::string_view a, std::string_view b) {
  const std::size_t n = a.size();
  if (n != b.size()) return false;
  const char* p = a.data();
  const char* q = b.data();
  auto word = [](const char* s) {
    std::uint64_t w;
    std::memcpy(&w, s, sizeof w);
    return w;
  };
  auto half = [](const char* s) {
    std::uint32_t w;
    std::memcpy(&w, s, sizeof w);
    return w;
  };
  if (n < 8) {
    if (n >= 4) return half(p) == half(q) && half(p + n - 4) == half(q + n - 4);  // overlapping
    for (std::size_t i = 0; i < n; ++i)
      if (p[i] != q[i]) return false;
    return true;
  }
  for (std::size_t i = 0; i + 8 < n; i += 8)
    if (word(p + i) != word(q + i)) return false;
  return word(p + n - 8) == word(q + n - 8);  // the last word, overlapping the one before
}

}  // namespace spindown
