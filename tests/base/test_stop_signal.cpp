// SIGINT/SIGTERM -> the stop flag and its pipe, installed by one StopSignals at a time and put
// back when it goes; the clock and host name helpers beside it.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <poll.h>
#include <stdexcept>
#include <thread>

#include "spindown/clock.hpp"
#include "spindown/host_name.hpp"
#include "spindown/stop_signal.hpp"

namespace spindown {
namespace {

bool readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  return ::poll(&p, 1, 0) == 1 && (p.revents & POLLIN);
}

TEST(StopSignals, SigtermSetsTheFlagAndWakesThePipe) {
  StopSignals stop;
  EXPECT_FALSE(stop.requested());
  EXPECT_FALSE(readable(stop.fd()));
  ASSERT_EQ(::raise(SIGTERM), 0);  // the process lives on: the handler only sets the flag
  EXPECT_TRUE(stop.requested());
  EXPECT_TRUE(readable(stop.fd()));
}

TEST(StopSignals, SigintToo) {
  StopSignals stop;
  ASSERT_EQ(::raise(SIGINT), 0);
  EXPECT_TRUE(stop.requested());
}

TEST(StopSignals, ASignalFromAnotherThreadEndsASleepAtOnce) {
  StopSignals stop;
  const auto start = std::chrono::steady_clock::now();
  std::thread t([] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    ::kill(::getpid(), SIGTERM);
  });
  EXPECT_FALSE(stop.sleep_for(std::chrono::seconds(10)));
  t.join();
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(5));
}

TEST(StopSignals, SleepsToTheEndWithoutAStop) {
  StopSignals stop;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_TRUE(stop.sleep_for(std::chrono::milliseconds(30)));
  EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(30));
}

TEST(StopSignals, RequestIsASignalWithoutTheKernel) {
  StopSignals stop;
  stop.request();
  EXPECT_TRUE(stop.requested());
  EXPECT_TRUE(readable(stop.fd()));
  EXPECT_FALSE(stop.sleep_for(std::chrono::seconds(10)));
}

TEST(StopSignals, OneAtATimeAndAFreshFlagForTheNext) {
  {
    StopSignals stop;
    EXPECT_THROW(StopSignals second, std::logic_error);
    stop.request();
  }
  StopSignals again;
  EXPECT_FALSE(again.requested());
}

TEST(StopSignals, PutsThePreviousHandlersBack) {
  struct sigaction ignore {}, before {}, after {};
  ignore.sa_handler = SIG_IGN;
  sigemptyset(&ignore.sa_mask);
  ASSERT_EQ(::sigaction(SIGTERM, &ignore, &before), 0);
  const auto old_pipe = ::signal(SIGPIPE, SIG_DFL);
  {
    StopSignals stop({.ignore_sigpipe = true});
    struct sigaction during {};
    ::sigaction(SIGTERM, nullptr, &during);
    EXPECT_NE(during.sa_handler, SIG_IGN);
    ::sigaction(SIGPIPE, nullptr, &during);
    EXPECT_EQ(during.sa_handler, SIG_IGN);
  }
  ::sigaction(SIGTERM, nullptr, &after);
  EXPECT_EQ(after.sa_handler, SIG_IGN);
  ::sigaction(SIGPIPE, nullptr, &after);
  EXPECT_EQ(after.sa_handler, SIG_DFL);
  ::sigaction(SIGTERM, &before, nullptr);
  ::signal(SIGPIPE, old_pipe);
}

TEST(Clock, WallMicrosecondsAreSinceTheEpoch) {
  const std::int64_t us = wall_us();
  EXPECT_GT(us, 1'600'000'000'000'000);  // after 2020
  EXPECT_LT(us, 4'100'000'000'000'000);  // before 2100
  const std::int64_t a = monotonic_ns();
  EXPECT_GE(monotonic_ns(), a);
}

TEST(HostName, NeverEmpty) { EXPECT_FALSE(host_name().empty()); }

}  // namespace
}  // namespace spindown
