#include "spindown/lcm_self_test.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fmt/format.h>
#include <random>
#include <unistd.h>

#include "spindown/lcm_loop.hpp"
#include "spindown/quiet_stderr.hpp"

namespace spindown {

LcmSelfTest run_lcm_self_test(const std::string& url, double timeout_s) {
  using clock = std::chrono::steady_clock;
  LcmSelfTest t;
  t.url = url;
  t.timeout_s = std::clamp(timeout_s, 0.1, 30.0);
  std::random_device rd;
  const auto nonce = fmt::format("{:08x}{:08x}", rd(), rd());
  t.channel = fmt::format("SPINDOWN_DOCTOR.{}.{}", ::getpid(), nonce.substr(0, 8));
  // LCM 1.3.1 prints its own advice to stderr when multicast does not work ("LCM self test
  // failed!!", a route hint with ifconfig); the doctor says it with the fix, so LCM's text is
  // held back while the test runs.
  QuietStderr quiet;
  LcmLoop loop(url);
  if (!loop.good()) return t;
  t.started = true;
  const std::string payload = "spindown doctor self-test " + nonce;
  const bool subscribed = loop.subscribe_raw(t.channel, [&](const LcmMessage& m) {
    if (static_cast<std::size_t>(m.size) == payload.size() && std::memcmp(m.data, payload.data(), payload.size()) == 0) {
      t.received = true;
      loop.stop();
    }
  });
  // LCM 1.3.1 has no socket to wait on when its own loopback self-test failed.
  t.receiving = subscribed && loop.can_receive();
  if (!t.receiving) return t;
  const auto start = clock::now();
  // One publish per 100 ms until one comes back or the time is up.
  loop.every(
      0.1,
      [&](std::int64_t) {
        if (loop.lcm().publish(t.channel, payload.data(), static_cast<unsigned>(payload.size())) != 0)
          ++t.publish_errors;
        ++t.published;
      },
      0);
  loop.run({.timeout_s = t.timeout_s, .max_wait_ms = 20, .max_failures = 0});
  t.round_trip_s = std::chrono::duration<double>(clock::now() - start).count();
  return t;
}

DoctorCheck check_lcm_self_test(const LcmSelfTest& t) {
  DoctorCheck c{"LCM self-test", CheckLevel::ok, "", ""};
  const std::string url = t.url.empty() ? "LCM's default URL" : t.url;
  if (!t.started) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("LCM cannot start on {} (for udpm: no multicast route, or the group/port is not valid)", url);
    c.fix = "ip route add 224.0.0.0/4 dev IFACE   # IFACE = the lab LAN interface, or lo for this host only (see 'multicast route')";
    return c;
  }
  if (!t.receiving) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("LCM started on {} but cannot receive: its own loopback test failed, so multicast sent on "
                           "this host does not come back (a firewall dropping the LCM port, or the route's interface)",
                           url);
    c.fix = "see 'firewall' and 'multicast route' above";
    return c;
  }
  if (!t.received) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("published {} message{} on {} ({} failed) over {:.3g} s and none came back: multicast is "
                           "dropped on this host",
                           t.published, t.published == 1 ? "" : "s", url, t.publish_errors, t.timeout_s);
    c.fix = "see 'firewall' and 'multicast route'; the route's interface must be up (ip link set IFACE up) and accept multicast "
            "(ip link set IFACE multicast on)";
    return c;
  }
  c.detail = fmt::format("a message on {} came back in {:.3g} ms ({})", url, t.round_trip_s * 1000, t.channel);
  return c;
}

}  // namespace spindown
