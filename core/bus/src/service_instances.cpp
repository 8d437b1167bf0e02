#include "spindown/service_instances.hpp"

#include <algorithm>
#include <ctime>
#include <fmt/format.h>

#include "spindown/session_id.hpp"

namespace spindown {

std::string instance_text(const ServiceInstance& i) {
  std::string started = "?";
  if (i.start_utime > 0) {
    const std::time_t s = static_cast<std::time_t>(i.start_utime / 1000000);
    std::tm local{};
    ::localtime_r(&s, &local);
    started = fmt::format("{:04}-{:02}-{:02} {:02}:{:02}:{:02}", local.tm_year + 1900, local.tm_mon + 1, local.tm_mday,
                          local.tm_hour, local.tm_min, local.tm_sec);
  }
  return fmt::format("host {} pid {} session {} started {}", i.host.empty() ? "?" : shown_name(i.host), i.pid,
                     session_text(i.session), started);
}

ServiceInstances::ServiceInstances(std::string service, std::string instance, double alive_s, std::size_t max_instances)
    : service_(std::move(service)),
      instance_(std::move(instance)),
      alive_us_(static_cast<std::int64_t>(alive_s * 1e6)),
      max_(std::max<std::size_t>(2, max_instances)) {}

void ServiceInstances::set_own(ServiceInstance own) {
  own.own = true;
  list_.insert(list_.begin(), std::move(own));
}

std::optional<std::string> ServiceInstances::heard(const status_t& s, std::int64_t recv_us) {
  if (s.service != service_ || s.instance != instance_) return std::nullopt;
  const auto session = static_cast<std::uint64_t>(s.source_session);
  auto it = std::find_if(list_.begin(), list_.end(), [&](const ServiceInstance& i) {
    return i.session == session && i.host == s.source_host && (session != 0 || i.pid == s.pid);
  });
  if (it == list_.end()) {
    if (list_.size() >= max_) {  // forget the one heard longest ago (never the own one)
      auto oldest = std::min_element(list_.begin(), list_.end(), [](const ServiceInstance& a, const ServiceInstance& b) {
        return !a.own && (b.own || a.last_heard_us < b.last_heard_us);
      });
      if (!oldest->own) list_.erase(oldest);
    }
    list_.push_back({s.source_host.empty() ? s.host : s.source_host, s.pid, session, s.start_utime, recv_us, false});
    it = list_.end() - 1;
  }
  if (it->own) return std::nullopt;  // our own heartbeat coming back
  it->last_heard_us = recv_us;
  it->pid = s.pid;
  const ServiceInstance& heard_one = *it;
  for (const ServiceInstance& other : list_) {
    if (&other == &heard_one || !(other.own || recv_us - other.last_heard_us <= alive_us_)) continue;
    const auto pair = std::minmax(other.session, heard_one.session);
    if (std::find(named_.begin(), named_.end(), std::pair(pair.first, pair.second)) != named_.end()) continue;
    named_.emplace_back(pair.first, pair.second);
    ++collisions_;
    return fmt::format("two {}s with the same instance name '{}' on this lab at once: {} and {}; they publish on one heartbeat "
                       "channel (SPINDOWN.{}.STATUS){}: give each its own --instance, or stop one",
                       service_, instance_, instance_text(other), instance_text(heard_one), instance_,
                       service_ == "fitter" ? " and the same benches' RUN and FIT" : "");
  }
  return std::nullopt;
}

std::vector<ServiceInstance> ServiceInstances::alive(std::int64_t now_us) const {
  std::vector<ServiceInstance> out;
  for (const ServiceInstance& i : list_)
    if (i.own || now_us - i.last_heard_us <= alive_us_) out.push_back(i);
  return out;
}

}  // namespace spindown
