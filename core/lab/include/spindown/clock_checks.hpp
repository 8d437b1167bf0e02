#pragma once
// Clocks across a lab for `spindown doctor`: is this PC's clock synchronized (the kernel's NTP
// state, as timedatectl's "System clock synchronized" reads it), and how far each lab PC's clock
// is from this one — from the utime that bridges and services put in the STATUS and CONFIG
// messages they send, against the time this PC received them. A skew does not change any fit
// (runs use the Arduino's own clock) but makes log times, watch ages and cross-host comparisons
// wrong.
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "spindown/doctor_check.hpp"

namespace spindown {

// What adjtimex(2) says: unsynchronized (STA_UNSYNC, or TIME_ERROR) and the estimated error.
struct KernelClockState {
  bool synchronized = false;
  long estimated_error_us = 0;
  long maximum_error_us = 0;
};
std::optional<KernelClockState> read_kernel_clock_state();  // nullopt when adjtimex fails
// sync_service: the NTP client found on this PC ("chrony", "systemd-timesyncd", "ntpd", "" none).
DoctorCheck check_clock_sync(const std::optional<KernelClockState>& state, const std::string& sync_service);

struct HostSkew {
  std::string host;
  std::vector<std::string> senders;  // "bridge bench-1", "fitter fitter", …
  std::size_t messages = 0;
  double median_s = 0;               // received − sent: > 0 the host's clock is behind this one
  double min_s = 0, max_s = 0;
};

// Collects (sent, received) pairs per host; keeps at most max_per_host pairs per host and
// max_hosts hosts, so a long listen stays small.
class ClockSkewTracker {
 public:
  explicit ClockSkewTracker(std::size_t max_per_host = 2000, std::size_t max_hosts = 256)
      : max_per_host_(max_per_host), max_hosts_(max_hosts) {}
  void add(const std::string& host, const std::string& sender, std::int64_t sent_utime, std::int64_t received_utime);
  std::vector<HostSkew> hosts() const;  // sorted by host name

 private:
  struct Entry {
    std::vector<double> skews_s;
    std::vector<std::string> senders;
    std::size_t messages = 0;
  };
  std::size_t max_per_host_, max_hosts_;
  std::map<std::string, Entry> by_host_;
};

// Skew thresholds: below warn_s ok, from warn_s warn, from fail_s fail (watch's ages and the
// logs' times are then off by more than a spin-down's whole coast).
inline constexpr double clock_skew_warn_s = 0.05;
inline constexpr double clock_skew_fail_s = 5.0;
// One check per host heard ("clock skew HOST"), or one skip when nothing was heard in listened_s.
std::vector<DoctorCheck> check_clock_skew(const std::vector<HostSkew>& hosts, const std::string& this_host,
                                          double listened_s);

}  // namespace spindown
