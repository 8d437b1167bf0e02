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
  const config_t c = lab_config("a", 2.0e-5);
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
  core.on_config("a", lab_config("a", 2.0e-5), 1);
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

// A logger's rotated files (issue 31): the same log cut into three files mid-coast, given in any
// order, are one session in time order: the same runs and numbers as the whole log; each file
// alone only has fragments. Files that overlap in time (another logger's copy) are sessions of
// their own.
TEST(LogRefit, RotatedFilesAreOneSessionInTimeOrder) {
  const Stream s = make_stream(2, 17);
  TempLog whole;
  write_log(whole.path, s, nullptr);
  const LogRefit all = refit_log(whole.path, FitterOptions{}, false);
  ASSERT_EQ(all.runs.size(), 2u);

  // The events again, cut at a third and two thirds: both cuts fall inside a coast.
  std::vector<lcm::LogEvent> events;
  std::vector<std::vector<unsigned char>> data;
  {
    lcm::LogFile in(whole.path, "r");
    while (const lcm::LogEvent* e = in.readNextEvent()) {
      data.emplace_back(static_cast<const unsigned char*>(e->data), static_cast<const unsigned char*>(e->data) + e->datalen);
      events.push_back(*e);
    }
  }
  const std::size_t n = events.size();
  const std::string base = ::testing::TempDir() + "spindown_rotated_" + std::to_string(::getpid());
  const std::vector<std::string> parts{base + "-1.lcm", base + "-2.lcm", base + "-3.lcm"};
  const std::size_t cut1 = 1 + all.runs[0].fit.run.cut_index / 5 + 20, cut2 = 1 + all.runs[1].fit.run.cut_index / 5 + 20;
  ASSERT_LT(cut1, cut2);
  ASSERT_LT(cut2, n);
  for (int k = 0; k < 3; ++k) {
    lcm::LogFile out(parts[k], "w");
    const std::size_t from = k == 0 ? 0 : k == 1 ? cut1 : cut2, to = k == 0 ? cut1 : k == 1 ? cut2 : n;
    for (std::size_t i = from; i < to; ++i) {
      lcm::LogEvent e = events[i];
      e.data = data[i].data();
      ASSERT_EQ(out.writeEvent(&e), 0);
    }
  }
  const auto sessions = log_sessions({parts[2], parts[0], parts[1]});
  ASSERT_EQ(sessions.size(), 1u);
  EXPECT_EQ(sessions[0], parts);
  const LogRefit r = refit_log_session(sessions[0], FitterOptions{}, false);
  ASSERT_EQ(r.runs.size(), 2u);
  EXPECT_EQ(r.session_files, parts);
  for (std::size_t k = 0; k < 2; ++k)
    EXPECT_EQ(run_fit_json(r.runs[k].fit).dump(), run_fit_json(all.runs[k].fit).dump()) << "run " << k + 1;
  std::size_t whole_alone = 0;
  for (const auto& p : parts)
    for (const auto& run : refit_log(p, FitterOptions{}, false).runs)
      whole_alone += !run.fit.run.partial() && run.fit.run.stopped;
  EXPECT_EQ(whole_alone, 0u) << "each file alone holds no run whole";

  // The whole log beside its own parts: two loggers' copies of one traffic never mix.
  const auto apart = log_sessions({whole.path, parts[1]});
  EXPECT_EQ(apart.size(), 2u);
  for (const auto& p : parts) std::remove(p.c_str());
}

TEST(LogRefit, AMissingLogIsAFailureNamingIt) {
  const LogRefit r = refit_log("/nonexistent/spindown.lcm", FitterOptions{}, false);
  ASSERT_FALSE(r.file.failures.empty());
  EXPECT_NE(r.file.failures.front().find("/nonexistent/spindown.lcm"), std::string::npos) << r.file.failures.front();
}

}  // namespace
}  // namespace spindown
