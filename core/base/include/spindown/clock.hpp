#pragma once
// The two clocks every spindown program reads: wall time in µs since the epoch (LCM's utime,
// receive times, status and log times) and a monotonic time for intervals and deadlines.
#include <chrono>
#include <cstdint>

namespace spindown {

// Microseconds since the Unix epoch (system_clock): what utime and recv_utime hold.
inline std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Monotonic nanoseconds (steady_clock), for latencies and intervals only: no meaning across
// processes or reboots.
inline std::int64_t monotonic_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Wall time that never steps: the wall clock as it read the first time this is called, advanced by
// the monotonic clock since. For the host times whose differences are durations (a bench's
// silence, a rate cap, how long a message waited past a gap) in a program that may see its wall
// clock stepped (an NTP correction, a laptop waking, an RTC kept in local time): a +1 h step is
// not an hour of silence. Never for times compared with another machine's (signatures' freshness
// and every utime sent keep wall_us()).
inline std::int64_t steady_wall_us() {
  static const std::int64_t anchor = wall_us() - monotonic_ns() / 1000;
  return monotonic_ns() / 1000 + anchor;
}

// A steady_clock deadline seconds from now (seconds may be fractional).
inline std::chrono::steady_clock::time_point steady_after(double seconds) {
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace spindown
