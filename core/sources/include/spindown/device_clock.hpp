#pragma once
// Turns a device's wrapping counter (Arduino millis(): 2^32 ms ≈ 49.7 days; micros(): 2^32 µs
// ≈ 71.6 min) into a monotonic µs time per clock epoch, and tells a wrap from a reset: a
// counter that steps back by little modulo 2^32 wrapped; one that steps back otherwise (the
// Arduino rebooted, e.g. when the port was opened) restarted, and a new epoch begins.
#include <cstdint>

namespace spindown {

class DeviceClock {
 public:
  struct Reading {
    std::int64_t time_us = 0;  // unwrapped device time in this epoch (µs)
    std::int32_t epoch = 0;    // resets seen so far
    bool reset = false;        // this reading started a new epoch
    bool wrapped = false;      // this reading crossed a counter wrap
  };

  // tick_us: µs per counter tick (1000 for millis(), 1 for micros()).
  // max_forward_ticks: the largest forward step, modulo the wrap, still read as a wrap
  // rather than a reset when the counter goes down (default: 10 minutes).
  explicit DeviceClock(std::int64_t tick_us = 1000, std::uint64_t wrap_ticks = 1ull << 32,
                       std::uint64_t max_forward_ticks = 0);

  Reading update(std::uint64_t ticks);

  // The next reading starts a new epoch (when there was a reading before): the caller knows
  // the device restarted (or switched protocol) by other means.
  void mark_reset() { pending_reset_ = true; }
  // Same device, new unit (protocol switch): counts as a reset.
  void set_tick_us(std::int64_t tick_us, std::uint64_t wrap_ticks = 1ull << 32);

  std::int32_t epoch() const { return epoch_; }
  std::int64_t tick_us() const { return tick_us_; }
  bool has_reading() const { return has_prev_; }

 private:
  std::int64_t tick_us_;
  std::uint64_t wrap_;
  std::uint64_t max_forward_;
  bool max_forward_default_;
  std::uint64_t prev_ = 0;
  std::int64_t wraps_ = 0;  // wraps in this epoch
  std::int32_t epoch_ = 0;
  bool has_prev_ = false;
  bool pending_reset_ = false;
};

}  // namespace spindown
