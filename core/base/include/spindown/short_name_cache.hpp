#pragma once
// A direct-mapped cache from a short name (an LCM channel, a bench id) to the caller's entry for
// it, asked once per message before any full lookup. Loggers interleave a handful of names in no
// fixed order, so "the same one as last time" guesses miss most of the time; a hash of the name
// picks one slot instead, and the caller confirms the entry there with one short compare. A miss
// (a new name, or two names sharing a slot) only costs the caller's full lookup, after which it
// remembers the answer in the slot. Entries are pointers owned elsewhere; nullptr is empty.
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string_view>

namespace spindown {

template <class T, std::size_t SlotBits = 6>
class ShortNameCache {
 public:
  // The slot for name: nullptr, or an entry that may or may not be name's.
  T*& slot(std::string_view name) { return slots_[index(name)]; }
  // Empties every slot holding entry (it is about to be destroyed).
  void forget(const T* entry) {
    for (T*& s : slots_)
      if (s == entry) s = nullptr;
  }

  // The top bits of a multiplicative hash over the name eight bytes at a time (the last word
  // overlapping the one before, as short_string_equal reads it); a name of 4 to 7 bytes (a
  // bench id) is two overlapping 4-byte halves in one word.
  static std::size_t index(std::string_view name) {
    constexpr std::uint64_t k = 0x9E3779B97F4A7C15ull;
    const char* p = name.data();
    const std::size_t n = name.size();
    std::uint64_t h = (n + 1) * k;
    auto word = [](const char* s) {
      std::uint64_t w;
      std::memcpy(&w, s, sizeof w);
      return w;
    };
    auto half = [](const char* s) {
      std::uint32_t w;
      std::memcpy(&w, s, sizeof w);
      return std::uint64_t{w};
    };
    if (n < 4) {
      for (std::size_t i = 0; i < n; ++i) h = (h ^ static_cast<unsigned char>(p[i])) * k;
    } else if (n < 8) {
      h = (h ^ (half(p) | half(p + n - 4) << 32)) * k;
    } else {
      for (std::size_t i = 0; i + 8 < n; i += 8) h = (h ^ word(p + i)) * k;
      h = (h ^ word(p + n - 8)) * k;
    }
    return static_cast<std::size_t>(h >> (64 - SlotBits));
  }

 private:
  std::array<T*, std::size_t{1} << SlotBits> slots_{};
};

}  // namespace spindown
