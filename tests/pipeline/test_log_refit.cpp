// refit_log (the library's `spindown refit`): an LCM log written as lcm-logger writes it gives
// the same runs and numbers as feeding its messages to a FitterCore directly; a live FIT in the
// log is kept when asked; each_run streams the runs without keeping them.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "fitter_test_support.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/log_refit.hpp"

namespace spindown {
namespace {

using namespace test;

struct TempLog {
  std::string path = ::testing::TempDir() + "spindown_log_refit_" + std::to_string(::getpid()) + ".lcm";
  ~TempLog() { std::remove(path.c_str()); }
};

// Two runs of bench "a" in batches of 5 samples, a CONFIG first; each message 100 ms apart.
void write_log(const std::string& path, const Stream& s, const fit_t* live_fit) {
  lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good());
  std::int64_t utime = 1'700'000'000'000'000;
  auto put = [&](const std::string& channel, const std::vector<unsigned char>& bytes) {
    lcm::LogEvent e;
    e.eventnum = 0;
    e.timestamp = utime += 100'000;
    e.channel = channel;
    e.datalen = static_cast<std::int32_t>(bytes.size());
    e.data = const_cast<unsigned char*>(bytes.data());
    ASSERT_EQ(log.writeEvent(&e), 0);
  };
  const config_t c = config("a", 2.0e-5);
  std::vector<unsigned char> cb(static_cast<std::size_t>(c.getEncodedSize()));
  c.encode(cb.data(), 0, static_cast<int>(cb.size()));
  put("SPINDOWN.a.CONFIG", cb);
  for (std::size_t i = 0; i < s.t_us.size(); i += 5) put("SPINDOWN.a.SAMPLE", encode(batch("a", s, i, 5, std::int64_t(i))));
  if (live_fit) {
    std::vector<unsigned char> fb(static_cast<std::size_t>(live_fit->getEncodedSize()));
    live_fit->encode(fb.data(), 0, static_cast<int>(fb.size()));
    put("SPINDOWN.a.FIT", fb);
  }
}

TEST(LogRefit, SameRunsAndNumbersAsTheCoreFedDirectly) {
  const Stream s = make_stream(2, 17);
  CollectingSink sink;
  FitterCore core({}, sink);
  core.on_config("a", config("a", 2.0e-5), 1);
  std::int64_t utime = 10;
  feed(core, "a", s, 5, utime);
  core.finish(utime);
  ASSERT_EQ(sink.fits.size(), 2u);

  const fit_t live = to_fit_message(sink.fits[0].fit, FitProvenance{"a", "config", 0, 0, 0, std::nullopt, "", 0}, 0);
  TempLog f;
  write_log(f.path, s, &live);
  const LogRefit r = refit_log(f.path, FitterOptions{}, true);
  ASSERT_TRUE(r.file.failures.empty()) << r.file.failures.front();
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_EQ(r.runs_fitted, 2u);
  EXPECT_EQ(r.bench_order, std::vector<std::string>{"a"});
  ASSERT_EQ(r.live.size(), 1u);  // the recorded FIT, kept as asked
  EXPECT_EQ(r.live[0].bench, "a");
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(r.runs[k].bench_source, "config");
    EXPECT_EQ(run_fit_json(r.runs[k].fit).dump(), run_fit_json(sink.fits[k].fit).dump()) << "run " << k + 1;
  }

  // Streamed: every run handed over as fitted, none kept.
  std::size_t streamed = 0;
  const LogRefit st = refit_log(f.path, FitterOptions{}, false, {}, {}, [&](RefitRun&& run) {
    EXPECT_EQ(run.bench, "a");
    ++streamed;
  });
  EXPECT_EQ(streamed, 2u);
  EXPECT_TRUE(st.runs.empty());
  EXPECT_EQ(st.runs_fitted, 2u);
}

TEST(LogRefit, AMissingLogIsAFailureNamingIt) {
  const LogRefit r = refit_log("/nonexistent/spindown.lcm", FitterOptions{}, false);
  ASSERT_FALSE(r.file.failures.empty());
  EXPECT_NE(r.file.failures.front().find("/nonexistent/spindown.lcm"), std::string::npos) << r.file.failures.front();
}

}  // namespace
}  // namespace spindown
