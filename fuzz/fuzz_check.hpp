#pragma once
// Invariants the fuzz targets assert on what the readers return. A broken invariant aborts with
// a message, which libFuzzer reports as a crash and saves the input.
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "spindown/recording.hpp"

#define FUZZ_CHECK(cond)                                                                   \
  do {                                                                                     \
    if (!(cond)) {                                                                         \
      std::fprintf(stderr, "fuzz invariant broken at %s:%d: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                        \
    }                                                                                      \
  } while (0)

namespace spindown::fuzz {

// Diagnostics end up in JSON (nlohmann::json refuses invalid UTF-8) and on terminals, so
// whatever bytes the input had, every message must be valid UTF-8.
inline bool valid_utf8(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size()) {
    const auto c = static_cast<unsigned char>(s[i]);
    std::size_t len = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (len == 0 || i + len > s.size()) return false;
    std::uint32_t cp = len == 1 ? c : len == 2 ? (c & 0x1F) : len == 3 ? (c & 0x0F) : (c & 0x07);
    for (std::size_t k = 1; k < len; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (cc & 0x3F);
    }
    const std::uint32_t min_cp[] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min_cp[len] || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) return false;
    i += len;
  }
  return true;
}

// What every reader promises about a Recording, whatever the input: matching arrays, finite
// numbers, time increasing between clock restarts, every skipped line counted, an empty
// recording explained by an error.
inline void check_recording(const Recording& rec, bool time_strictly_increasing = true,
                            bool empty_needs_error = true) {
  FUZZ_CHECK(rec.t_s.size() == rec.value.size());
  FUZZ_CHECK(rec.lines_skipped <= rec.lines_read);
  std::size_t next_restart = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    FUZZ_CHECK(std::isfinite(rec.t_s[i]));
    FUZZ_CHECK(std::isfinite(rec.value[i]));
    const bool restart = next_restart < rec.clock_restarts.size() && rec.clock_restarts[next_restart] == i;
    if (restart) ++next_restart;
    if (i > 0 && !restart && time_strictly_increasing) FUZZ_CHECK(rec.t_s[i] > rec.t_s[i - 1]);
  }
  for (std::size_t k = 0; k < rec.clock_restarts.size(); ++k) {
    FUZZ_CHECK(rec.clock_restarts[k] <= rec.size());
    if (k > 0) FUZZ_CHECK(rec.clock_restarts[k] > rec.clock_restarts[k - 1]);
  }
  for (const Diagnostic& d : rec.diagnostics) {
    FUZZ_CHECK(!d.message.empty());
    if (!valid_utf8(d.message)) std::fprintf(stderr, "message: %s\n", d.message.c_str());
    FUZZ_CHECK(valid_utf8(d.message));
  }
  if (rec.empty() && empty_needs_error) FUZZ_CHECK(rec.has_errors());
}

}  // namespace spindown::fuzz
