#include "spindown/publish_health.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>

namespace spindown {

PublishHealth::PublishHealth(PublishHealthOptions options) : opt_(std::move(options)) {}

void PublishHealth::report(std::int64_t now_us, const std::string& text) {
  last_error_ = text;
  last_error_utime_ = now_us;
  if (now_us < next_report_us_) return;
  next_report_us_ = now_us + static_cast<std::int64_t>(opt_.report_every_s * 1e6);
  fmt::print(stderr, "{}: {}\n", opt_.program, text);
}

void PublishHealth::sent(int rc, std::string_view channel, std::int64_t now_us) {
  const int err = errno;
  std::lock_guard lock(mutex_);
  if (rc == 0) {
    if (failing_) {
      failing_ = false;
      fmt::print(stderr, "{}: publishing works again ({} sends failed in all)\n", opt_.program, failures_);
      next_report_us_ = 0;
    }
    return;
  }
  ++failures_;
  failing_ = true;
  const std::string why = rc < 0 && err != 0 ? std::strerror(err) : fmt::format("LCM returned {}", rc);
  report(now_us, fmt::format("cannot publish on {}: {} ({} sends failed so far): results are not reaching the lab; "
                             "is there a route for the LCM group (ip route add 224.0.0.0/4 dev IFACE)?",
                             channel, why, failures_));
}

void PublishHealth::heartbeat_sent(int rc, std::string_view channel, std::int64_t utime, std::int64_t now_us,
                                   bool judge_echo) {
  sent(rc, channel, now_us);
  std::lock_guard lock(mutex_);
  if (judge_echo) {
    check_echo(now_us);
  } else {
    oldest_unechoed_us_ = 0;  // judged afresh from the next heartbeat on
  }
  if (rc == 0 && oldest_unechoed_us_ == 0) {
    oldest_unechoed_us_ = now_us;
    oldest_unechoed_utime_ = utime;
  }
}

void PublishHealth::check_echo(std::int64_t now_us) {
  if (oldest_unechoed_us_ == 0 || now_us - oldest_unechoed_us_ < static_cast<std::int64_t>(opt_.echo_grace_s * 1e6))
    return;
  ++unheard_;
  deaf_ = true;
  report(now_us, fmt::format("my own heartbeats do not come back ({} unheard, none for {:.1f} s): what I publish may "
                             "not reach the lab (no multicast route to the LCM group on the lab's interface? a "
                             "firewall?)",
                             unheard_, 1e-6 * double(now_us - oldest_unechoed_us_)));
}

void PublishHealth::echoed(std::int64_t utime) {
  std::lock_guard lock(mutex_);
  echoed_utime_ = std::max(echoed_utime_, utime);
  if (oldest_unechoed_us_ != 0 && utime >= oldest_unechoed_utime_) {
    oldest_unechoed_us_ = 0;
    if (deaf_) {
      deaf_ = false;
      fmt::print(stderr, "{}: my heartbeats come back again ({} were unheard)\n", opt_.program, unheard_);
      next_report_us_ = 0;
    }
  }
}

std::int64_t PublishHealth::failures() const {
  std::lock_guard lock(mutex_);
  return failures_;
}

std::int64_t PublishHealth::unheard_heartbeats() const {
  std::lock_guard lock(mutex_);
  return unheard_;
}

std::string PublishHealth::last_error() const {
  std::lock_guard lock(mutex_);
  return last_error_;
}

std::int64_t PublishHealth::last_error_utime() const {
  std::lock_guard lock(mutex_);
  return last_error_utime_;
}

}  // namespace spindown
