// PublishHealth: a service's own view of whether what it publishes goes anywhere (issue 31):
// failed sends with errno's words, heartbeats that never come back, counted for the heartbeat.
#include <gtest/gtest.h>

#include <cerrno>

#include "spindown/publish_health.hpp"

namespace spindown {
namespace {

constexpr std::int64_t sec = 1'000'000;

TEST(PublishHealth, AFailedSendIsCountedAndNamed) {
  PublishHealth h({.program = "test", .report_every_s = 10, .echo_grace_s = 3});
  h.sent(0, "SPINDOWN.a.FIT", 1 * sec);
  EXPECT_EQ(h.failures(), 0);
  errno = ENETUNREACH;
  h.sent(-1, "SPINDOWN.a.FIT", 2 * sec);
  errno = ENETUNREACH;
  h.sent(-1, "SPINDOWN.a.RUN", 3 * sec);
  EXPECT_EQ(h.failures(), 2);
  EXPECT_NE(h.last_error().find("cannot publish on SPINDOWN.a.RUN: Network is unreachable"), std::string::npos)
      << h.last_error();
  EXPECT_NE(h.last_error().find("2 sends failed"), std::string::npos) << h.last_error();
  EXPECT_EQ(h.last_error_utime(), 3 * sec);
  h.sent(0, "SPINDOWN.a.FIT", 4 * sec);  // works again: the count stays for the heartbeat
  EXPECT_EQ(h.failures(), 2);
}

TEST(PublishHealth, AHeartbeatThatNeverComesBackIsUnheard) {
  PublishHealth h({.program = "test", .report_every_s = 10, .echo_grace_s = 3});
  // Heartbeats every second that come back: nothing unheard.
  for (int i = 0; i < 5; ++i) {
    h.heartbeat_sent(0, "SPINDOWN.fitter.STATUS", i * sec, i * sec);
    h.echoed(i * sec);
  }
  EXPECT_EQ(h.unheard_heartbeats(), 0);
  // Sent without error, never back (the route points elsewhere): unheard once past the grace.
  for (int i = 5; i < 12; ++i) h.heartbeat_sent(0, "SPINDOWN.fitter.STATUS", i * sec, i * sec);
  EXPECT_EQ(h.unheard_heartbeats(), 4);  // at 8, 9, 10 and 11 s
  EXPECT_NE(h.last_error().find("heartbeats do not come back"), std::string::npos) << h.last_error();
  h.echoed(11 * sec);
  h.heartbeat_sent(0, "SPINDOWN.fitter.STATUS", 12 * sec, 12 * sec);
  EXPECT_EQ(h.unheard_heartbeats(), 4);
  // After a stall of the service itself, no heartbeat is judged.
  h.heartbeat_sent(0, "SPINDOWN.fitter.STATUS", 30 * sec, 30 * sec, false);
  h.heartbeat_sent(0, "SPINDOWN.fitter.STATUS", 31 * sec, 31 * sec);
  EXPECT_EQ(h.unheard_heartbeats(), 4);
}

}  // namespace
}  // namespace spindown
