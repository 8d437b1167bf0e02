#include "spindown/clock_checks.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <sys/timex.h>

namespace spindown {

std::optional<KernelClockState> read_kernel_clock_state() {
  timex tx{};
  tx.modes = 0;  // read only
  const int state = ::adjtimex(&tx);
  if (state < 0) return std::nullopt;
  KernelClockState s;
  s.synchronized = state != TIME_ERROR && !(tx.status & STA_UNSYNC);
  s.estimated_error_us = tx.esterror;
  s.maximum_error_us = tx.maxerror;
  return s;
}

DoctorCheck check_clock_sync(const std::optional<KernelClockState>& state, const std::string& sync_service) {
  DoctorCheck c{"clock sync", CheckLevel::ok, "", ""};
  const std::string service = sync_service.empty() ? "no NTP client found" : "NTP client: " + sync_service;
  if (!state) {
    c.level = CheckLevel::skip;
    c.detail = fmt::format("cannot read the kernel's clock state (adjtimex); {}", service);
    return c;
  }
  if (!state->synchronized) {
    c.level = CheckLevel::warn;
    c.detail = fmt::format("this PC's clock is not synchronized ({}): log times and ages disagree between lab PCs", service);
    c.fix = sync_service.empty() ? "apt-get install systemd-timesyncd && timedatectl set-ntp true   # or chrony; the same NTP server on every lab PC"
                                 : "timedatectl set-ntp true; timedatectl timesync-status   # or chronyc sources: is the NTP server reachable?";
    return c;
  }
  c.detail = fmt::format("synchronized ({}), estimated error {:.3g} ms", service, state->estimated_error_us / 1000.0);
  return c;
}

void ClockSkewTracker::add(const std::string& host, const std::string& sender, std::int64_t sent_utime,
                           std::int64_t received_utime) {
  if (sent_utime <= 0 || received_utime <= 0) return;  // a sender that leaves utime at 0 says nothing
  auto it = by_host_.find(host);
  if (it == by_host_.end()) {
    if (by_host_.size() >= max_hosts_) return;
    it = by_host_.emplace(host, Entry{}).first;
  }
  Entry& e = it->second;
  ++e.messages;
  if (e.skews_s.size() < max_per_host_) e.skews_s.push_back(double(received_utime - sent_utime) * 1e-6);
  if (std::find(e.senders.begin(), e.senders.end(), sender) == e.senders.end() && e.senders.size() < 16)
    e.senders.push_back(sender);
}

std::vector<HostSkew> ClockSkewTracker::hosts() const {
  std::vector<HostSkew> out;
  for (const auto& [host, e] : by_host_) {
    if (e.skews_s.empty()) continue;
    std::vector<double> v = e.skews_s;
    std::sort(v.begin(), v.end());
    HostSkew h;
    h.host = host;
    h.senders = e.senders;
    h.messages = e.messages;
    const std::size_t n = v.size();
    h.median_s = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    h.min_s = v.front();
    h.max_s = v.back();
    out.push_back(std::move(h));
  }
  return out;
}

std::vector<DoctorCheck> check_clock_skew(const std::vector<HostSkew>& hosts, const std::string& this_host,
                                          double listened_s) {
  std::vector<DoctorCheck> out;
  if (hosts.empty()) {
    out.push_back({"clock skew", CheckLevel::skip,
                   fmt::format("no bridge or service heard in {:.3g} s (no STATUS/CONFIG message to compare clocks with)",
                               listened_s),
                   ""});
    return out;
  }
  for (const auto& h : hosts) {
    std::string senders;
    for (const auto& s : h.senders) senders += (senders.empty() ? "" : ", ") + s;
    const double skew = h.median_s;
    const std::string where = h.host == this_host ? " (this PC)" : "";
    DoctorCheck c{"clock skew " + (h.host.empty() ? std::string("(no host name)") : h.host), CheckLevel::ok, "", ""};
    const std::string direction = std::abs(skew) < 0.0005 ? "matches this PC's"
                                  : skew > 0             ? fmt::format("is {:.3g} s behind this PC's", skew)
                                                         : fmt::format("is {:.3g} s ahead of this PC's", -skew);
    c.detail = fmt::format("clock{} {} (median of {} message{} from {}; range {:+.3g} … {:+.3g} s, network delay included)",
                           where, direction, h.messages, h.messages == 1 ? "" : "s", senders, h.min_s, h.max_s);
    if (std::abs(skew) >= clock_skew_warn_s) {
      c.level = std::abs(skew) >= clock_skew_fail_s ? CheckLevel::fail : CheckLevel::warn;
      c.fix = fmt::format("on {} and on this PC: timedatectl set-ntp true (or chrony), the same NTP server for the whole lab",
                          h.host.empty() ? "that host" : h.host);
    }
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace spindown
