#include "spindown/lcm_status.hpp"

#include <algorithm>
#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

namespace spindown {

StatusHeartbeat::StatusHeartbeat(std::string service, std::string instance, std::int64_t start_us,
                                 double interval_s, std::string host, int pid)
    : service_(std::move(service)),
      instance_(std::move(instance)),
      host_(host.empty() ? host_name() : std::move(host)),
      pid_(pid == 0 ? static_cast<int>(getpid()) : pid),
      start_us_(start_us),
      interval_us_(std::max<std::int64_t>(1, static_cast<std::int64_t>(interval_s * 1e6))),
      next_due_us_(start_us) {}

void StatusHeartbeat::set_counter(std::string_view name, std::int64_t value) {
  for (auto& [n, v] : counters_)
    if (n == name) {
      v = value;
      return;
    }
  counters_.emplace_back(std::string(name), value);
}

void StatusHeartbeat::add_counter(std::string_view name, std::int64_t delta) {
  set_counter(name, counter(name) + delta);
}

std::int64_t StatusHeartbeat::counter(std::string_view name) const {
  for (const auto& [n, v] : counters_)
    if (n == name) return v;
  return 0;
}

void StatusHeartbeat::set_gauge(std::string_view name, double value) {
  for (auto& [n, v] : gauges_)
    if (n == name) {
      v = value;
      return;
    }
  gauges_.emplace_back(std::string(name), value);
}

void StatusHeartbeat::set_error(std::string text, std::int64_t utime) {
  last_error_ = std::move(text);
  last_error_utime_ = utime;
}

void StatusHeartbeat::mark_sent(std::int64_t now_us) {
  next_due_us_ += interval_us_;
  // After a stall, beat again one interval from now rather than catching up in a burst.
  if (next_due_us_ <= now_us) next_due_us_ = now_us + interval_us_;
}

status_t StatusHeartbeat::message(std::int64_t now_us) const {
  return status_message(now_us,
                        {.service = service_,
                         .instance = instance_,
                         .host = host_,
                         .pid = pid_,
                         .state = state_,
                         .uptime_s = double(now_us - start_us_) * 1e-6,
                         .last_error = last_error_,
                         .last_error_utime = last_error_utime_},
                        counters_, gauges_);
}

int StatusHeartbeat::publish(lcm::LCM& lcm, const std::string& channel, std::int64_t now_us) {
  const status_t st = message(now_us);
  mark_sent(now_us);
  return lcm.publish(channel, &st);
}

std::optional<std::int64_t> find_counter(const status_t& status, std::string_view name) {
  const auto n = std::min<std::size_t>(status.counter_name.size(), status.counter_value.size());
  for (std::size_t i = 0; i < n; ++i)
    if (status.counter_name[i] == name) return status.counter_value[i];
  return std::nullopt;
}

std::optional<double> find_gauge(const status_t& status, std::string_view name) {
  const auto n = std::min<std::size_t>(status.gauge_name.size(), status.gauge_value.size());
  for (std::size_t i = 0; i < n; ++i)
    if (status.gauge_name[i] == name) return status.gauge_value[i];
  return std::nullopt;
}

}  // namespace spindown
