#pragma once
// LCM's own round trip on a URL for `spindown doctor`: start LCM, subscribe to a channel no one
// else uses (SPINDOWN_DOCTOR.<pid>.<nonce>: outside SPINDOWN.*, so loggers and the fitter ignore
// it), publish a few messages and wait, bounded in time, for one to come back. A udpm URL without
// a multicast route fails to start; a firewall dropping multicast or a closed loopback loses the
// messages.
#include <string>

#include "spindown/doctor_check.hpp"

namespace spindown {

struct LcmSelfTest {
  std::string url;
  std::string channel;
  bool started = false;    // lcm_create succeeded
  bool receiving = false;  // LCM set up its receive socket (LCM 1.3.1's udpm runs its own loopback
                           // self-test there; when that fails it has no socket to wait on)
  bool received = false;   // one of our messages came back
  int published = 0;       // messages sent (every 100 ms until received or the timeout)
  int publish_errors = 0;
  double round_trip_s = 0; // first publish to first receipt
  double timeout_s = 0;
};

// Bounded: at most timeout_s (clamped to 0.1 … 30 s) and one publish per 100 ms.
LcmSelfTest run_lcm_self_test(const std::string& url, double timeout_s);

// ok when a message came back; fail otherwise, with the likely cause and fix.
DoctorCheck check_lcm_self_test(const LcmSelfTest& result);

}  // namespace spindown
