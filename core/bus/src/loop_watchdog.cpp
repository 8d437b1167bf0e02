#include "spindown/loop_watchdog.hpp"

#include <algorithm>

#include "spindown/clock.hpp"

namespace spindown {

void feed_watchdog_from_loop(LcmLoop& loop, ServiceNotifier& notifier,
                             std::function<bool(std::int64_t now_ns)> progressing) {
  if (notifier.ping_period_s() > 0) {
    // Called four times per ping period; the notifier sends at most one ping per period.
    loop.every(
        std::min(1.0, notifier.ping_period_s() / 4),
        [&notifier, progressing = std::move(progressing)](std::int64_t) {
          const std::int64_t now = monotonic_ns();
          notifier.watchdog(!progressing || progressing(now), now);
        },
        0);
  }
  if (notifier.has_stall_hook()) loop.every(0.05, [&notifier](std::int64_t) { notifier.stall_point(); });
}

}  // namespace spindown
