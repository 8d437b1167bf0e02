#include "spindown/device_clock.hpp"

#include <algorithm>

namespace spindown {

namespace {
std::uint64_t default_forward(std::int64_t tick_us, std::uint64_t wrap) {
  // Ten minutes of ticks, but never more than half the counter range.
  const std::uint64_t ten_min = 600'000'000ull / std::uint64_t(std::max<std::int64_t>(tick_us, 1));
  return std::min(ten_min, wrap / 2);
}
}  // namespace

DeviceClock::DeviceClock(std::int64_t tick_us, std::uint64_t wrap_ticks, std::uint64_t max_forward_ticks)
    : tick_us_(std::max<std::int64_t>(tick_us, 1)),
      wrap_(std::max<std::uint64_t>(wrap_ticks, 2)),
      max_forward_(max_forward_ticks ? max_forward_ticks : default_forward(tick_us_, wrap_)),
      max_forward_default_(max_forward_ticks == 0) {}

void DeviceClock::set_tick_us(std::int64_t tick_us, std::uint64_t wrap_ticks) {
  tick_us_ = std::max<std::int64_t>(tick_us, 1);
  wrap_ = std::max<std::uint64_t>(wrap_ticks, 2);
  if (max_forward_default_) max_forward_ = default_forward(tick_us_, wrap_);
  pending_reset_ = true;
}

DeviceClock::Reading DeviceClock::update(std::uint64_t ticks) {
  ticks %= wrap_;
  Reading r;
  if (has_prev_ && pending_reset_) {
    r.reset = true;
  } else if (has_prev_ && ticks < prev_) {
    // Down: a wrap only when the forward distance around the wrap is small.
    const std::uint64_t forward = wrap_ - prev_ + ticks;
    if (forward <= max_forward_) {
      ++wraps_;
      r.wrapped = true;
    } else {
      r.reset = true;
    }
  }
  if (r.reset) {
    ++epoch_;
    wraps_ = 0;
  }
  pending_reset_ = false;
  has_prev_ = true;
  prev_ = ticks;
  r.epoch = epoch_;
  r.time_us = (wraps_ * static_cast<std::int64_t>(wrap_) + static_cast<std::int64_t>(ticks)) * tick_us_;
  return r;
}

}  // namespace spindown
