#pragma once
// systemd's notify protocol for spindown's services (units with Type=notify and WatchdogSec=),
// through libsystemd's sd_notify: READY=1 once a service does its job (subscribed, device
// loop running), WATCHDOG=1 from the service's main loop while that loop and the work behind it
// make progress, STOPPING=1 when it stops, STATUS= lines for `systemctl status`. Outside
// systemd (no NOTIFY_SOCKET) every call does nothing; without WATCHDOG_USEC no pings are sent.
//
// watchdog() is meant to be called from the main loop itself (a timer of LcmLoop, the bridge's
// serial loop): a loop that hangs stops calling it, and systemd kills and restarts the service
// after WatchdogSec. It pings at most every half watchdog interval, and not at all while the
// caller says the work behind the loop (a worker or writer thread) is stuck.
//
// Test hook (not an option): with SPINDOWN_TEST_STALL_FILE=PATH in the environment,
// stall_point() blocks its caller (the main loop) while PATH exists, at most 60 s, after
// saying STATUS=test stall; tests/integration/service_watchdog.sh freezes a loop that way and
// sees the pings stop.
#include <cstdint>
#include <string>
#include <string_view>

namespace spindown {

class ServiceNotifier {
 public:
  ServiceNotifier();  // reads NOTIFY_SOCKET, WATCHDOG_USEC (and WATCHDOG_PID) once

  bool active() const { return active_; }
  double watchdog_s() const { return watchdog_us_ * 1e-6; }        // 0: no watchdog asked for
  double ping_period_s() const { return watchdog_us_ * 0.5e-6; }   // 0: no pings

  void ready(std::string_view status = {});
  void status(std::string_view status);
  void stopping(std::string_view status = {});
  // WATCHDOG=1 when a ping is due and progressing; otherwise nothing (a stuck worker is said
  // once in STATUS=). now_ns: monotonic (monotonic_ns()).
  void watchdog(bool progressing, std::int64_t now_ns);
  void watchdog(bool progressing = true);

  // The test hook above; returns at once unless SPINDOWN_TEST_STALL_FILE is set and exists.
  void stall_point();
  bool has_stall_hook() const { return !stall_file_.empty(); }

  // How long a worker thread may go without a sign of life before it counts as stuck: half the
  // watchdog interval, at least 2 s (an idle worker wakes every 0.5 s).
  std::int64_t stuck_after_ns() const;

  std::int64_t pings() const { return pings_; }

 private:
  bool send(const std::string& state);

  bool active_ = false;
  std::int64_t watchdog_us_ = 0;
  std::int64_t next_ping_ns_ = 0;
  std::int64_t pings_ = 0;
  bool said_stuck_ = false;
  std::string stall_file_;
};

}  // namespace spindown
