#include "spindown/lcm_self_test.hpp"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fmt/format.h>
#include <lcm/lcm.h>
#include <random>
#include <fcntl.h>
#include <unistd.h>

namespace spindown {

namespace {

struct Receipt {
  std::string nonce;
  bool received = false;
};

// A plain C callback (LCM 1.3.1's C++ subscription templates trip UBSan in its own header).
extern "C" void on_self_test_message(const lcm_recv_buf_t* rbuf, const char*, void* user) {
  auto* r = static_cast<Receipt*>(user);
  const auto size = static_cast<std::size_t>(rbuf->data_size);
  if (size == r->nonce.size() && std::memcmp(rbuf->data, r->nonce.data(), size) == 0) r->received = true;
}

// LCM 1.3.1 prints its own advice to stderr when multicast does not work ("LCM self test
// failed!!", a route hint with ifconfig); the doctor says it with the fix, so LCM's text is held
// back while the test runs.
class QuietStderr {
 public:
  QuietStderr() : saved_(::dup(2)) {
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved_ >= 0 && null >= 0) ::dup2(null, 2);
    if (null >= 0) ::close(null);
  }
  ~QuietStderr() {
    if (saved_ >= 0) {
      ::dup2(saved_, 2);
      ::close(saved_);
    }
  }
  QuietStderr(const QuietStderr&) = delete;
  QuietStderr& operator=(const QuietStderr&) = delete;

 private:
  int saved_;
};

}  // namespace

LcmSelfTest run_lcm_self_test(const std::string& url, double timeout_s) {
  using clock = std::chrono::steady_clock;
  LcmSelfTest t;
  t.url = url;
  t.timeout_s = std::clamp(timeout_s, 0.1, 30.0);
  std::random_device rd;
  const auto nonce = fmt::format("{:08x}{:08x}", rd(), rd());
  t.channel = fmt::format("SPINDOWN_DOCTOR.{}.{}", ::getpid(), nonce.substr(0, 8));
  QuietStderr quiet;
  lcm_t* lcm = lcm_create(url.empty() ? nullptr : url.c_str());
  if (!lcm) return t;
  t.started = true;
  Receipt receipt{"spindown doctor self-test " + nonce, false};
  lcm_subscription_t* sub = lcm_subscribe(lcm, t.channel.c_str(), on_self_test_message, &receipt);
  // LCM 1.3.1 returns fd -1 when its receive setup failed, and lcm_handle_timeout would then
  // FD_SET(-1) and abort: never wait on it.
  t.receiving = sub && lcm_get_fileno(lcm) >= 0;
  if (!t.receiving) {
    if (sub) lcm_unsubscribe(lcm, sub);
    lcm_destroy(lcm);
    return t;
  }
  const auto start = clock::now();
  const auto deadline = start + std::chrono::duration_cast<clock::duration>(std::chrono::duration<double>(t.timeout_s));
  auto next_publish = start;
  // Bounded in count as well as time: one publish per 100 ms, one wait per 20 ms at most.
  for (int i = 0; i < 2000 && !receipt.received && clock::now() < deadline; ++i) {
    if (clock::now() >= next_publish) {
      if (lcm_publish(lcm, t.channel.c_str(), receipt.nonce.data(), static_cast<unsigned>(receipt.nonce.size())) != 0)
        ++t.publish_errors;
      ++t.published;
      next_publish += std::chrono::milliseconds(100);
    }
    if (lcm_handle_timeout(lcm, 20) < 0) break;
  }
  t.received = receipt.received;
  t.round_trip_s = std::chrono::duration<double>(clock::now() - start).count();
  if (sub) lcm_unsubscribe(lcm, sub);
  lcm_destroy(lcm);
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
