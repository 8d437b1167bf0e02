#include "spindown/service_notifier.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <unistd.h>

#include <systemd/sd-daemon.h>

#include "spindown/clock.hpp"

namespace spindown {

ServiceNotifier::ServiceNotifier() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  active_ = socket && *socket;
  std::uint64_t usec = 0;
  // > 0 only when WATCHDOG_USEC is set (and WATCHDOG_PID, if set, is this process).
  if (active_ && sd_watchdog_enabled(0, &usec) > 0) watchdog_us_ = static_cast<std::int64_t>(usec);
  if (const char* f = std::getenv("SPINDOWN_TEST_STALL_FILE")) stall_file_ = f;
}

bool ServiceNotifier::send(const std::string& state) {
  if (!active_) return false;
  return sd_notify(0, state.c_str()) > 0;
}

void ServiceNotifier::ready(std::string_view status) {
  send(status.empty() ? std::string("READY=1") : "READY=1\nSTATUS=" + std::string(status));
}

void ServiceNotifier::status(std::string_view status) { send("STATUS=" + std::string(status)); }

void ServiceNotifier::stopping(std::string_view status) {
  send(status.empty() ? std::string("STOPPING=1") : "STOPPING=1\nSTATUS=" + std::string(status));
}

void ServiceNotifier::watchdog(bool progressing, std::int64_t now_ns) {
  if (watchdog_us_ <= 0) return;
  if (!progressing) {
    if (!said_stuck_) send("STATUS=stuck: the work behind the main loop makes no progress (watchdog pings held back)");
    said_stuck_ = true;
    return;
  }
  if (said_stuck_) {
    send("STATUS=running again");
    said_stuck_ = false;
  }
  if (now_ns < next_ping_ns_) return;
  if (send("WATCHDOG=1")) ++pings_;
  next_ping_ns_ = now_ns + watchdog_us_ * 500;  // half the interval, in ns
}

void ServiceNotifier::watchdog(bool progressing) { watchdog(progressing, monotonic_ns()); }

std::int64_t ServiceNotifier::stuck_after_ns() const {
  return std::max<std::int64_t>(2'000'000'000, watchdog_us_ * 500);
}

void ServiceNotifier::stall_point() {
  if (stall_file_.empty() || ::access(stall_file_.c_str(), F_OK) != 0) return;
  send("STATUS=test stall: main loop blocked while " + stall_file_ + " exists");
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (::access(stall_file_.c_str(), F_OK) == 0 && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  send("STATUS=test stall over");
}

}  // namespace spindown
