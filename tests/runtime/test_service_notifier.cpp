// ServiceNotifier speaks systemd's notify protocol to a real unix datagram socket standing in
// for systemd (NOTIFY_SOCKET): READY=1, WATCHDOG=1 at most every half interval and never while
// the work is stuck, STOPPING=1; silent without NOTIFY_SOCKET or without WATCHDOG_USEC.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>
#include <vector>

#include "spindown/service_notifier.hpp"

namespace spindown {
namespace {

class FakeSystemd : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (std::filesystem::temp_directory_path() / ("spindown-notify-" + std::to_string(::getpid()))).string();
    ::unlink(path_.c_str());
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    ASSERT_GE(fd_, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    ASSERT_LT(path_.size(), sizeof a.sun_path);
    std::copy(path_.begin(), path_.end(), a.sun_path);
    ASSERT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    ::setenv("NOTIFY_SOCKET", path_.c_str(), 1);
    ::setenv("WATCHDOG_USEC", "200000", 1);
    ::unsetenv("WATCHDOG_PID");
  }
  void TearDown() override {
    ::close(fd_);
    ::unlink(path_.c_str());
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
  }
  // Everything received so far (the datagrams are sent before the calls return).
  std::vector<std::string> received() {
    std::vector<std::string> out;
    char buf[4096];
    for (;;) {
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n < 0) break;
      out.emplace_back(buf, static_cast<std::size_t>(n));
    }
    return out;
  }
  std::string path_;
  int fd_ = -1;
};

TEST_F(FakeSystemd, ReadyWatchdogStopping) {
  ServiceNotifier n;
  EXPECT_TRUE(n.active());
  EXPECT_DOUBLE_EQ(n.watchdog_s(), 0.2);
  EXPECT_DOUBLE_EQ(n.ping_period_s(), 0.1);
  n.ready("subscribed");
  EXPECT_EQ(received(), (std::vector<std::string>{"READY=1\nSTATUS=subscribed"}));

  const std::int64_t t = 1'000'000'000;
  n.watchdog(true, t);
  n.watchdog(true, t + 50'000'000);   // within half the interval: no second ping
  EXPECT_EQ(received(), (std::vector<std::string>{"WATCHDOG=1"}));
  n.watchdog(true, t + 100'000'000);  // half the interval later: the next one
  EXPECT_EQ(received(), (std::vector<std::string>{"WATCHDOG=1"}));
  EXPECT_EQ(n.pings(), 2);

  // Stuck: no pings, said once; going again: said, and pinged.
  n.watchdog(false, t + 300'000'000);
  n.watchdog(false, t + 400'000'000);
  const auto stuck = received();
  ASSERT_EQ(stuck.size(), 1u);
  EXPECT_TRUE(stuck[0].starts_with("STATUS=stuck")) << stuck[0];
  n.watchdog(true, t + 500'000'000);
  EXPECT_EQ(received(), (std::vector<std::string>{"STATUS=running again", "WATCHDOG=1"}));

  n.stopping();
  EXPECT_EQ(received(), (std::vector<std::string>{"STOPPING=1"}));
}

TEST_F(FakeSystemd, NoWatchdogWithoutWatchdogUsec) {
  ::unsetenv("WATCHDOG_USEC");
  ServiceNotifier n;
  EXPECT_EQ(n.ping_period_s(), 0);
  n.watchdog(true, 1);
  n.ready();
  EXPECT_EQ(received(), (std::vector<std::string>{"READY=1"}));
}

TEST_F(FakeSystemd, WatchdogForAnotherPidIsNotOurs) {
  ::setenv("WATCHDOG_PID", "1", 1);
  ServiceNotifier n;
  EXPECT_EQ(n.ping_period_s(), 0);
  ::unsetenv("WATCHDOG_PID");
}

TEST_F(FakeSystemd, SilentOutsideSystemd) {
  ::unsetenv("NOTIFY_SOCKET");
  ServiceNotifier n;
  EXPECT_FALSE(n.active());
  n.ready();
  n.watchdog(true, 1);
  n.stopping();
  EXPECT_TRUE(received().empty());
}

TEST_F(FakeSystemd, StuckAfterIsHalfTheIntervalAtLeastTwoSeconds) {
  ::setenv("WATCHDOG_USEC", "30000000", 1);
  EXPECT_EQ(ServiceNotifier().stuck_after_ns(), 15'000'000'000);
  ::setenv("WATCHDOG_USEC", "1000000", 1);
  EXPECT_EQ(ServiceNotifier().stuck_after_ns(), 2'000'000'000);
}

}  // namespace
}  // namespace spindown
