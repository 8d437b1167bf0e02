// build_session_report takes an LCM log's start time from its first event with a time set: the
// first event's for sound logs, the first sound event's after damage at the start. The friction trends take
// each run's combined-model c_v, c_c from motor_health's combined_friction.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "spindown/lcm_log_reader.hpp"
#include "spindown/build_session_report.hpp"

namespace spindown {
namespace {

// One event in lcm_eventlog's layout; the lengths can be given wrong on purpose.
std::string event_bytes(std::int64_t number, std::int64_t utime, const std::string& channel, const std::string& data,
                        std::optional<std::int32_t> channel_len = {}, std::optional<std::int32_t> data_len = {}) {
  std::string out;
  auto put = [&out](std::uint64_t v, int bytes) {
    for (int i = bytes - 1; i >= 0; --i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  put(lcm_log_magic, 4);
  put(static_cast<std::uint64_t>(number), 8);
  put(static_cast<std::uint64_t>(utime), 8);
  put(static_cast<std::uint32_t>(channel_len.value_or(static_cast<std::int32_t>(channel.size()))), 4);
  put(static_cast<std::uint32_t>(data_len.value_or(static_cast<std::int32_t>(data.size()))), 4);
  return out + channel + data;
}

class SessionReportStart : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("spindown-test-session-report-" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  // Writes bytes to NAME.lcm and checks the report's start time.
  void expect_start(const std::string& name, const std::string& bytes, std::optional<double> want) {
    const std::string path = (dir_ / (name + ".lcm")).string();
    std::ofstream(path, std::ios::binary) << bytes;
    const std::vector<std::string> paths{path};
    SessionReportOptions options;
    options.read.format = FileFormat::lcm_log;  // so that a damaged first word is still read as a log
    const SessionReport report = build_session_report(paths, options);
    ASSERT_EQ(report.files.size(), 1u) << name;
    EXPECT_EQ(report.files[0].start_unix_s, want) << name;
  }

  std::filesystem::path dir_;
};

constexpr std::int64_t t1 = 1'700'000'000'123'456, t2 = 1'700'000'001'000'000;
const double start1 = static_cast<double>(t1) * 1e-6, start2 = static_cast<double>(t2) * 1e-6;

TEST_F(SessionReportStart, SoundLogsTakeTheFirstEventsTime) {
  expect_start("two", event_bytes(1, t1, "SPINDOWN.a.STATUS", "xyz") + event_bytes(2, t2, "X", "abc"), start1);
  expect_start("one_exactly", event_bytes(7, t1, "X", std::string(3000, 'd')), start1);
  expect_start("empty_data", event_bytes(1, t1, "X", ""), start1);
  expect_start("long_channel", event_bytes(1, t1, std::string(999, 'c'), "d") + event_bytes(2, t2, "X", "d"), start1);
}

TEST_F(SessionReportStart, DamageAtTheStartIsSkippedToTheFirstSoundEvent) {
  const std::string second = event_bytes(2, t2, "X", "abc");
  expect_start("zero_time", event_bytes(1, 0, "X", "abc") + second, start2);
  expect_start("negative_time", event_bytes(1, -5, "X", "abc") + second, start2);
  expect_start("garbage_first", std::string(40, 'g') + second, start2);
  expect_start("no_channel", event_bytes(1, t1, "", "abc") + second, start2);
  expect_start("channel_too_long", event_bytes(1, t1, std::string(1000, 'c'), "d") + second, start2);
  expect_start("negative_data", event_bytes(1, t1, "X", "abc", {}, -3) + second, start2);
  expect_start("past_the_end", event_bytes(1, t1, "X", "abc", {}, 1 << 20) + second, start2);
  expect_start("truncated_only", event_bytes(1, t1, "X", "abcdef").substr(0, 31), std::nullopt);
  expect_start("header_cut", event_bytes(1, t1, "X", "abc").substr(0, 20), std::nullopt);
  expect_start("empty", "", std::nullopt);
}

RunFit fit_with_combined(double c3, double c3_se, double c4, double c4_se, bool converged = true) {
  RunFit fit;
  ModelFit viscous;
  viscous.kind = ModelKind::viscous;
  viscous.converged = true;
  viscous.params = {{"c1", 9.0, 1.0, "N*m*s/rad"}};
  ModelFit combined;
  combined.kind = ModelKind::combined;
  combined.converged = converged;
  combined.params = {{"c3", c3, c3_se, "N*m*s/rad"}, {"c4", c4, c4_se, "N*m"}, {"omega0", 300, 1, "rad/s"}};
  fit.models = {viscous, combined};
  return fit;
}

TEST(CombinedFriction, IsTheCombinedModelsC3AndC4) {
  const auto f = combined_friction(fit_with_combined(1.8e-7, 2e-9, 1.1e-4, 3e-6));
  ASSERT_TRUE(f.has_value());
  EXPECT_EQ(f->c_viscous, 1.8e-7);
  EXPECT_EQ(f->c_viscous_stderr, 2e-9);
  EXPECT_EQ(f->c_coulomb, 1.1e-4);
  EXPECT_EQ(f->c_coulomb_stderr, 3e-6);
  // A standard error the fit could not give counts as unknown (0), which the trend's weights
  // and the report's error bars treat as they treated NaN.
  const auto no_se = combined_friction(fit_with_combined(1.8e-7, std::nan(""), 1.1e-4, 3e-6));
  ASSERT_TRUE(no_se.has_value());
  EXPECT_EQ(no_se->c_viscous_stderr, 0.0);
  EXPECT_FALSE(combined_friction(fit_with_combined(1.8e-7, 2e-9, 1.1e-4, 3e-6, false)).has_value());
  EXPECT_FALSE(combined_friction(fit_with_combined(std::nan(""), 2e-9, 1.1e-4, 3e-6)).has_value());
  EXPECT_FALSE(combined_friction(RunFit{}).has_value());
}

TEST(CombinedFriction, FeedsTheBenchTrend) {
  SessionReport report;
  for (int i = 0; i < 3; ++i) {
    ReportRun r;
    r.bench = "b1";
    r.fit = fit_with_combined(1e-7 * (i + 1), 1e-9, 1e-4, 1e-6, i != 1);  // the second run's fit failed
    report.runs.push_back(r);
  }
  summarize_session(report);
  ASSERT_EQ(report.benches.size(), 1u);
  EXPECT_EQ(report.benches[0].viscous.value, (std::vector<double>{1e-7, 3e-7}));
  EXPECT_EQ(report.benches[0].coulomb.std_error, (std::vector<double>{1e-6, 1e-6}));
  EXPECT_EQ(report.benches[0].viscous.x, (std::vector<double>{1, 3}));
}

}  // namespace
}  // namespace spindown
