// Two instances of one service name alive at once (two fitters both "fitter") are named once,
// with host, pid, session and start time; a restart (the old one gone quiet) is not a collision.
#include <gtest/gtest.h>

#include <string>

#include "spindown/service_instances.hpp"

namespace spindown {
namespace {

constexpr std::int64_t t0 = 1'700'000'000'000'000;
constexpr std::int64_t sec = 1'000'000;

status_t fitter_status(const std::string& host, int pid, std::uint64_t session, const std::string& name = "fitter") {
  status_t s{};
  s.service = "fitter";
  s.instance = name;
  s.host = host;
  s.pid = pid;
  s.source_host = host;
  s.source_session = static_cast<std::int64_t>(session);
  s.start_utime = t0 - 60 * sec;
  return s;
}

TEST(ServiceInstances, TwoAliveAtOnceAreNamedOnce) {
  ServiceInstances seen("fitter", "fitter");
  EXPECT_FALSE(seen.heard(fitter_status("pc-a", 100, 1), t0));
  EXPECT_FALSE(seen.heard(fitter_status("pc-a", 100, 1), t0 + sec));
  const auto text = seen.heard(fitter_status("pc-b", 200, 2), t0 + sec);
  ASSERT_TRUE(text);
  EXPECT_NE(text->find("two fitters with the same instance name 'fitter' on this lab at once: host pc-a pid 100 session "
                       "0000000000000001"),
            std::string::npos)
      << *text;
  EXPECT_NE(text->find("host pc-b pid 200 session 0000000000000002"), std::string::npos) << *text;
  EXPECT_NE(text->find("--instance"), std::string::npos);
  EXPECT_FALSE(seen.heard(fitter_status("pc-a", 100, 1), t0 + 2 * sec));
  EXPECT_FALSE(seen.heard(fitter_status("pc-b", 200, 2), t0 + 2 * sec));
  EXPECT_EQ(seen.collisions(), 1);
  EXPECT_EQ(seen.alive(t0 + 2 * sec).size(), 2u);
  EXPECT_FALSE(seen.heard(fitter_status("pc-c", 300, 3, "fitter-2"), t0));  // another name: not this one's
}

TEST(ServiceInstances, ARestartIsNotACollisionAndTheOwnInstanceCounts) {
  ServiceInstances seen("fitter", "fitter", 5.0);
  seen.set_own({"pc-a", 100, 1, t0, 0, true});
  EXPECT_FALSE(seen.heard(fitter_status("pc-a", 100, 1), t0));  // our own heartbeat coming back
  const auto text = seen.heard(fitter_status("pc-b", 200, 2), t0);
  ASSERT_TRUE(text);  // the own instance is always alive
  ServiceInstances other("fitter", "fitter", 5.0);
  EXPECT_FALSE(other.heard(fitter_status("pc-a", 100, 1), t0));
  EXPECT_FALSE(other.heard(fitter_status("pc-a", 101, 4), t0 + 10 * sec));  // restarted: the old one is quiet
  EXPECT_EQ(other.collisions(), 0);
  EXPECT_EQ(other.alive(t0 + 10 * sec).size(), 1u);
}

}  // namespace
}  // namespace spindown
