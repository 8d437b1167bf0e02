#pragma once
// The heartbeat every service publishes (status_t on SPINDOWN.<service>.STATUS or
// SPINDOWN.<bench>.STATUS, design §3): who it is, its state, named monotonic counters and named
// gauges, and the last problem in words. StatusHeartbeat keeps the values between beats and
// builds the message; services set counters by name as they go and publish when due().
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <spindown/status_t.hpp>

#include "spindown/host_name.hpp"

namespace lcm {
class LCM;
}

namespace spindown {

// Who a heartbeat is from and how it stands: the fields every status_t carries beside its counters
// and gauges.
struct StatusHeader {
  std::string_view service, instance, host;
  std::int32_t pid = 0;
  std::string_view state;
  double uptime_s = 0;
  std::string_view last_error;
  std::int64_t last_error_utime = 0;
};

// Appends named (name, value) counters or gauges to a status message in the order given (lcm-spy's
// rows stay put), keeping its counts: what status_message builds from, and what a service adds
// to the core's heartbeat (the fitter's queue, the logger's gate).
template <class Counters>
void add_counters(status_t& st, const Counters& counters) {
  for (const auto& [name, value] : counters) {
    st.counter_name.emplace_back(name);
    st.counter_value.push_back(static_cast<std::int64_t>(value));
  }
  st.ncounters = static_cast<std::int32_t>(st.counter_name.size());
}
template <class Gauges>
void add_gauges(status_t& st, const Gauges& gauges) {
  for (const auto& [name, value] : gauges) {
    st.gauge_name.emplace_back(name);
    st.gauge_value.push_back(static_cast<double>(value));
  }
  st.ngauges = static_cast<std::int32_t>(st.gauge_name.size());
}

// The one builder of a status_t: the header, then the named counters and gauges (add_counters,
// add_gauges). StatusHeartbeat, the fitter's and the bridge's heartbeats are all made here.
template <class Counters, class Gauges>
status_t status_message(std::int64_t utime, const StatusHeader& h, const Counters& counters, const Gauges& gauges) {
  status_t st{};
  st.utime = utime;
  st.service = std::string(h.service);
  st.instance = std::string(h.instance);
  st.host = std::string(h.host);
  st.pid = h.pid;
  st.state = std::string(h.state);
  st.uptime_s = h.uptime_s;
  add_counters(st, counters);
  add_gauges(st, gauges);
  st.last_error = std::string(h.last_error);
  st.last_error_utime = h.last_error_utime;
  return st;
}

class StatusHeartbeat {
 public:
  // host empty = host_name(); pid 0 = getpid(). interval_s: how often due() says yes.
  StatusHeartbeat(std::string service, std::string instance, std::int64_t start_us, double interval_s = 1.0,
                  std::string host = {}, int pid = 0);

  void set_state(std::string state) { state_ = std::move(state); }
  const std::string& state() const { return state_; }

  // Counters and gauges keep the order in which they were first set, so lcm-spy rows stay put.
  void set_counter(std::string_view name, std::int64_t value);
  void add_counter(std::string_view name, std::int64_t delta = 1);
  std::int64_t counter(std::string_view name) const;  // 0 when never set
  void set_gauge(std::string_view name, double value);

  void set_error(std::string text, std::int64_t utime);
  const std::string& last_error() const { return last_error_; }

  // True when a beat is due at now_us; mark_sent() schedules the next one.
  bool due(std::int64_t now_us) const { return now_us >= next_due_us_; }
  void mark_sent(std::int64_t now_us);

  status_t message(std::int64_t now_us) const;

  // Publishes message(now_us) on channel and marks it sent; returns lcm's result (0 = ok).
  int publish(lcm::LCM& lcm, const std::string& channel, std::int64_t now_us);

 private:
  std::string service_, instance_, host_;
  int pid_;
  std::int64_t start_us_;
  std::int64_t interval_us_;
  std::int64_t next_due_us_;
  std::string state_ = "starting";
  std::vector<std::pair<std::string, std::int64_t>> counters_;
  std::vector<std::pair<std::string, double>> gauges_;
  std::string last_error_;
  std::int64_t last_error_utime_ = 0;
};

// Looks up a counter or gauge of a received status message by name.
std::optional<std::int64_t> find_counter(const status_t& status, std::string_view name);
std::optional<double> find_gauge(const status_t& status, std::string_view name);

}  // namespace spindown
