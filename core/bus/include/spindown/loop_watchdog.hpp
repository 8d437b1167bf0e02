#pragma once
// systemd's watchdog fed by an LcmLoop's own thread: WATCHDOG=1 from one of the loop's timers
// (so a loop stuck in a handler or in LCM stops the pings), and only while progressing() says
// the work behind the loop moves (a worker or writer thread's last sign of life). With
// SPINDOWN_TEST_STALL_FILE set, a second timer is the notifier's stall point (the test hook that
// blocks this loop). Nothing is added when the service has no watchdog (no WATCHDOG_USEC).
#include <functional>

#include "spindown/lcm_loop.hpp"
#include "spindown/service_notifier.hpp"

namespace spindown {

// progressing(monotonic ns) -> bool; empty: the loop running is progress enough.
void feed_watchdog_from_loop(LcmLoop& loop, ServiceNotifier& notifier,
                             std::function<bool(std::int64_t now_ns)> progressing = {});

}  // namespace spindown
