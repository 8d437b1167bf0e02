#include "spindown/lcm_loop.hpp"

#include <algorithm>
#include <cerrno>
#include <fmt/format.h>
#include <poll.h>
#include <regex.h>
#include <thread>

#include "spindown/clock.hpp"
#include "spindown/stop_signal.hpp"

namespace spindown {

using Clock = std::chrono::steady_clock;

struct LcmLoop::Subscription {
  LcmLoop* loop = nullptr;
  std::function<void(const LcmMessage&)> handle;
  std::function<bool(std::string_view)> accept;
  lcm_subscription_t* lcm = nullptr;
};

std::string LcmDecodeError::text() const {
  return fmt::format("{}: {} bytes that do not decode as {}: {}", channel, size, type, why);
}

LcmLoop::LcmLoop(const std::string& url) : lcm_(url) {}

LcmLoop::~LcmLoop() { unsubscribe_all(); }

bool LcmLoop::subscribe_raw(const std::string& channel_regex, std::function<void(const LcmMessage&)> handler,
                            LcmSubscribeOptions options) {
  if (!lcm_.good()) return false;
  // LCM 1.3.1 leaks its copy of a pattern that does not compile: the pattern is checked here first,
  // as LCM compiles it (POSIX extended, anchored at both ends).
  {
    regex_t re;
    if (::regcomp(&re, ("^" + channel_regex + "$").c_str(), REG_NOSUB | REG_EXTENDED) != 0) return false;
    ::regfree(&re);
  }
  auto sub = std::make_unique<Subscription>();
  sub->loop = this;
  sub->handle = std::move(handler);
  sub->accept = std::move(options.accept);
  sub->lcm = lcm_subscribe(lcm_.getUnderlyingLCM(), channel_regex.c_str(), &LcmLoop::dispatch, sub.get());
  if (!sub->lcm) return false;
  lcm_subscription_set_queue_capacity(sub->lcm, options.queue_capacity);
  subscriptions_.push_back(std::move(sub));
  receive_fd_.store(lcm_.getFileno(), std::memory_order_relaxed);
  return true;
}

void LcmLoop::unsubscribe_all() {
  for (auto& sub : subscriptions_) lcm_unsubscribe(lcm_.getUnderlyingLCM(), sub->lcm);
  subscriptions_.clear();
}

// LCM's C callback: nothing may leave it but a normal return.
void LcmLoop::dispatch(const lcm_recv_buf_t* rbuf, const char* channel, void* user) noexcept {
  auto* sub = static_cast<Subscription*>(user);
  LcmLoop& loop = *sub->loop;
  if (loop.pending_) return;  // an earlier handler of this message threw: run() rethrows that first
  const LcmMessage m{channel, rbuf->data, static_cast<std::int64_t>(rbuf->data_size), rbuf->recv_utime};
  try {
    if (sub->accept && !sub->accept(m.channel)) return;
    sub->handle(m);
  } catch (const std::exception& e) {
    if (!loop.handler_error_) {
      loop.pending_ = std::current_exception();
      return;
    }
    try {
      loop.handler_error_(m, e);
    } catch (...) {
      loop.pending_ = std::current_exception();
    }
  } catch (...) {
    loop.pending_ = std::current_exception();
  }
}

void LcmLoop::decode_failed(const LcmMessage& m, const char* type, std::string why) {
  ++decode_errors_;
  last_decode_error_ = {std::string(m.channel), type, m.size, std::move(why), m.recv_utime};
  if (decode_report_) decode_report_(last_decode_error_);
}

int LcmLoop::handle_one() {
  const int rc = lcm_.handle();
  if (pending_) std::rethrow_exception(std::exchange(pending_, nullptr));
  return rc;
}

void LcmLoop::every(double period_s, std::function<void(std::int64_t)> fn, double first_after_s) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::max(0.0, period_s)));
  const auto first = first_after_s < 0 ? period
                                       : std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(first_after_s));
  timers_.push_back({period, Clock::now() + first, std::move(fn)});
}

void LcmLoop::run_timers() {
  if (timers_.empty()) return;
  const auto now = Clock::now();
  const std::int64_t now_us = wall_us();
  for (Timer& t : timers_) {
    if (t.period > Clock::duration::zero() && now < t.next) continue;
    t.fn(now_us);
    // A steady cadence; after a stall, one period from now rather than a burst to catch up.
    t.next += t.period;
    if (t.next <= now) t.next = now + t.period;
  }
}

bool LcmLoop::can_receive() { return lcm_.good() && lcm_.getFileno() >= 0; }

bool LcmLoop::messages_waiting() const {
  const int fd = receive_fd_.load(std::memory_order_relaxed);
  if (fd < 0) return false;
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 0) > 0 && (p.revents & POLLIN);
}

LcmLoopEnd LcmLoop::run(const LcmRunOptions& o) {
  const auto deadline = o.timeout_s > 0 ? steady_after(o.timeout_s) : Clock::time_point::max();
  const auto longest = std::chrono::milliseconds(std::max(0, o.max_wait_ms));
  const auto stop_requested = [&] { return stop_ || (o.stop && o.stop->requested()); };
  int failures = 0;
  for (;;) {
    if (stop_requested()) {
      stop_.store(false);
      return LcmLoopEnd::stopped;
    }
    const auto now = Clock::now();
    if (now >= deadline) return LcmLoopEnd::deadline;
    auto wake = std::min(deadline, now + longest);
    for (const Timer& t : timers_)
      if (t.period > Clock::duration::zero()) wake = std::min(wake, t.next);
    const auto wait_ms = std::chrono::ceil<std::chrono::milliseconds>(std::max(wake - now, Clock::duration::zero()));

    // lcm_handle_timeout, with the stop signal's pipe beside LCM's socket. LCM 1.3.1 gives -1
    // for a udpm URL whose receive setup failed (lcm_handle_timeout would FD_SET(-1)).
    int status = -1;
    const int fd = lcm_.good() ? lcm_.getFileno() : -1;
    if (fd >= 0) {
      pollfd fds[2] = {{fd, POLLIN, 0}, {o.stop ? o.stop->fd() : -1, POLLIN, 0}};
      const int n = ::poll(fds, 2, static_cast<int>(wait_ms.count()));
      if (n < 0)
        status = errno == EINTR ? 0 : -1;
      else if (fds[0].revents & POLLIN)
        status = handle_one();
      else
        status = fds[0].revents & (POLLERR | POLLHUP | POLLNVAL) ? -1 : 0;
    }
    if (status < 0) {
      if (o.max_failures >= 0 && ++failures > o.max_failures) return LcmLoopEnd::failed;
      if (!stop_requested()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    } else {
      failures = 0;
    }
    run_timers();
  }
}

void LcmLoop::drain(int quiet_ms, double at_most_s) {
  const auto until = steady_after(at_most_s);
  for (int i = 0; i < 10'000'000 && Clock::now() < until; ++i) {
    const int fd = lcm_.good() ? lcm_.getFileno() : -1;
    if (fd < 0) return;
    pollfd p{fd, POLLIN, 0};
    const int n = ::poll(&p, 1, quiet_ms);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0 || !(p.revents & POLLIN)) return;
    if (handle_one() < 0) return;
  }
}

}  // namespace spindown
