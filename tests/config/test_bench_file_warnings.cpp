// A bench file whose [bench] K_b and [motor] datasheet constants disagree is named in a warning
// (BenchFile::warnings, from the same reading spindown-bridge does); one that agrees is not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#include "spindown/bench_file.hpp"
#include "spindown/bridge_settings.hpp"

namespace spindown {
namespace {

class BenchFileWarnings : public ::testing::Test {
 protected:
  std::filesystem::path dir = std::filesystem::temp_directory_path() /
                              ("spindown-bench-warnings-" + std::to_string(::getpid()));
  void SetUp() override { std::filesystem::create_directories(dir); }
  void TearDown() override { std::filesystem::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    const auto p = dir / name;
    std::ofstream(p) << text;
    return p.string();
  }
};

// The held-out case's file: K_b 0.0080926 V·s/rad (1180 rpm/V) against a datasheet of 1416 rpm/V.
TEST_F(BenchFileWarnings, TwentyPercentApartIsNamedWithWhichOneIsUsed) {
  const std::string path = write("bench6.toml", R"(bench_id = "bench6"
[bench]
inertia_kg_m2 = 1.12687602e-5
kb_v_s_per_rad = 0.0080926
[motor]
speed_constant_rpm_per_v = 1416
no_load_speed_rpm = 14200
no_load_current_a = 0.045
)");
  const BenchFile f = load_bench_file(path);
  ASSERT_EQ(f.warnings.size(), 1u);
  const std::string& w = f.warnings[0];
  EXPECT_EQ(w.rfind(path + ": warning: ", 0), 0u) << w;
  EXPECT_NE(w.find("[bench] kb_v_s_per_rad = 0.0080926 V·s/rad"), std::string::npos) << w;
  EXPECT_NE(w.find("[motor] speed_constant_rpm_per_v = 1416 rpm/V"), std::string::npos) << w;
  EXPECT_NE(w.find("disagree by 20 %"), std::string::npos) << w;  // 1416/1180 − 1
  EXPECT_NE(w.find("the fits use [bench]'s K_b"), std::string::npos) << w;
  // The fits do use [bench]'s.
  EXPECT_DOUBLE_EQ(f.params.kb_v_s_per_rad, 0.0080926);
  // spindown-bridge reads the same words.
  BridgeSettings s;
  load_bridge_settings(path, s);
  EXPECT_EQ(s.warnings, f.warnings);
}

TEST_F(BenchFileWarnings, ConstantsOfOneMotorAgreeAndSayNothing) {
  // The same datasheet twice (K_b derived from 1180 rpm/V, torque constant 8.09 mN·m/A: 0.03 % apart).
  const BenchFile same = load_bench_file(write("same.toml", R"([bench]
speed_constant_rpm_per_v = 1180
[motor]
speed_constant_rpm_per_v = 1180
torque_constant_nm_per_a = 0.00809
)"));
  EXPECT_TRUE(same.warnings.empty()) << same.warnings.front();
  // A K_b measured 8 % off the datasheet on a bench whose file states a 5 % tolerance: within 2σ.
  const BenchFile measured = load_bench_file(write("measured.toml", R"([bench]
kb_v_s_per_rad = 0.00874
kb_error_pct = 5
[motor]
speed_constant_rpm_per_v = 1180
)"));
  EXPECT_TRUE(measured.warnings.empty()) << measured.warnings.front();
  // Without a [bench] K_b there is nothing to contradict (the fits take the CONFIG's or the lab's).
  EXPECT_TRUE(load_bench_file(write("motor-only.toml", "[motor]\nspeed_constant_rpm_per_v = 1416\n")).warnings.empty());
}

TEST_F(BenchFileWarnings, TheTorqueConstantIsTheSameNumberAsKb) {
  const BenchFile f = load_bench_file(write("torque.toml", R"([bench]
kb_v_s_per_rad = 0.0080926
[motor]
torque_constant_nm_per_a = 0.0097
)"));
  ASSERT_EQ(f.warnings.size(), 1u);
  EXPECT_NE(f.warnings[0].find("[motor] torque_constant_nm_per_a = 0.0097 N·m/A"), std::string::npos) << f.warnings[0];
  EXPECT_NE(f.warnings[0].find("disagree by 20 %"), std::string::npos) << f.warnings[0];
}

TEST(KbDisagreement, TheThresholdIsTwoPercentOrTwiceTheStatedTolerance) {
  EXPECT_TRUE(kb_disagreement("f", 1.0, "a", 0, 1.019, "b").empty());
  EXPECT_FALSE(kb_disagreement("f", 1.0, "a", 0, 1.021, "b").empty());
  EXPECT_FALSE(kb_disagreement("f", 1.021, "a", 0, 1.0, "b").empty());  // either way round
  EXPECT_TRUE(kb_disagreement("f", 1.0, "a", 0.05, 1.09, "b").empty());
  EXPECT_FALSE(kb_disagreement("f", 1.0, "a", 0.05, 1.11, "b").empty());
}

}  // namespace
}  // namespace spindown
