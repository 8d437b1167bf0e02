// The terminal progress line: silent when disabled (not a terminal), at most one draw per
// interval, rate and ETA from the clock, erased at the end.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <string>
#include <unistd.h>

#include "spindown/progress.hpp"

namespace spindown {
namespace {

// A pipe to capture what the reporter writes.
struct Pipe {
  int fd[2]{-1, -1};
  Pipe() {
    EXPECT_EQ(::pipe(fd), 0);
    ::fcntl(fd[0], F_SETFL, O_NONBLOCK);
  }
  ~Pipe() {
    ::close(fd[0]);
    ::close(fd[1]);
  }
  std::string drain() const {
    std::string out;
    char buf[4096];
    for (int i = 0; i < 1000; ++i) {
      const ssize_t n = ::read(fd[0], buf, sizeof buf);
      if (n <= 0) break;
      out.append(buf, static_cast<std::size_t>(n));
    }
    return out;
  }
};

TEST(ProgressReporter, SilentWhenDisabled) {
  Pipe p;
  double now = 0;
  {
    ProgressReporter r(p.fd[1], false, ProgressReporter::Unit::bytes, 0.1, [&] { return now; });
    for (int i = 0; i < 100; ++i) {
      now += 1;
      r.update(i, 100, "refit: x.lcm", "runs 1");
    }
    EXPECT_EQ(r.draws(), 0);
  }
  EXPECT_EQ(p.drain(), "");
  EXPECT_FALSE(ProgressReporter::is_terminal(p.fd[1]));
}

TEST(ProgressReporter, ThrottledAndClearedAtTheEnd) {
  Pipe p;
  double now = 100;
  ProgressReporter r(p.fd[1], true, ProgressReporter::Unit::bytes, 0.1, [&] { return now; });
  r.update(10, 1000, "report", "");  // nothing has been slow yet: no line
  EXPECT_EQ(r.draws(), 0);
  // 1000 updates over 2 s: at most one draw per 0.1 s.
  for (int i = 0; i < 1000; ++i) {
    now += 0.002;
    r.update(i, 1000, "report", "runs 2/5");
  }
  EXPECT_GE(r.draws(), 15);
  EXPECT_LE(r.draws(), 21);
  r.finish();
  r.update(999, 1000, "report", "");  // after finish: ignored
  const std::string out = p.drain();
  EXPECT_NE(out.find("\rreport  "), std::string::npos);
  EXPECT_NE(out.find("runs 2/5"), std::string::npos);
  EXPECT_TRUE(out.ends_with("\r\x1b[K")) << "the line is erased at the end";
}

TEST(ProgressReporter, LineShowsDoneTotalRateAndEta) {
  const std::string line = ProgressReporter::format_line("refit: lab.lcm", 2'500'000, 10'000'000,
                                                         ProgressReporter::Unit::bytes, "3 runs fitted", 2.0, 0);
  EXPECT_EQ(line, "refit: lab.lcm  2.5 MB / 10.0 MB (25 %)  1.2 MB/s  ETA 6 s  3 runs fitted");
  const std::string msgs =
      ProgressReporter::format_line("x", 300, 0, ProgressReporter::Unit::messages, "", 3.0, 0);
  EXPECT_EQ(msgs, "x  300  100/s");
  EXPECT_EQ(ProgressReporter::format_line("abcdef", 1, 2, ProgressReporter::Unit::messages, "", 1.0, 4), "abcd");
}

}  // namespace
}  // namespace spindown
