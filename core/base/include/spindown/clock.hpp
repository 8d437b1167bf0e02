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

// A steady_clock deadline seconds from now (seconds may be fractional).
inline std::chrono::steady_clock::time_point steady_after(double seconds) {
  return std::chrono::steady_clock::now() +
         std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(seconds));
}

}  // namespace spindown
