// Motor health: verdict levels against a baseline and a datasheet, significance (noise never
// flags a motor), thresholds from the bench file, the datasheet's k_M·I0, the lab's time rules,
// the missing reference, TOML errors naming file and key, and the baseline's TOML section.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "spindown/bench_file.hpp"
#include "spindown/health_baseline.hpp"
#include "spindown/health_file.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown {
namespace {

constexpr double J = 1.12687602e-5;
constexpr double cv0 = 1.822e-7;   // the lab's motor (design §1)
constexpr double cc0 = 1.1389e-4;
constexpr double w0 = 346.0;

double stop_time(double c_v, double c_c, double omega0) {
  return J / c_v * std::log(1 + c_v * omega0 / c_c);
}

// A combined fit as fit_run would report it, without fitting.
RunFit combined_fit(double c_v, double se_v, double c_c, double se_c, double omega0 = w0) {
  RunFit fit;
  fit.bench.inertia_kg_m2 = J;
  ModelFit m;
  m.kind = ModelKind::combined;
  m.converged = true;
  m.omega0 = omega0;
  m.params = {{"c3", c_v, se_v, "N*m*s/rad"}, {"c4", c_c, se_c, "N*m"}, {"omega0", omega0, 0.1, "rad/s"}};
  m.rate = c_v / J;
  m.decel = c_c / J;
  m.t_stop_pred_s = stop_time(c_v, c_c, omega0);
  fit.models.push_back(m);
  fit.best = "combined";
  fit.run.number = 1;
  fit.run.t_cut_s = 10;
  fit.run.stopped = true;
  fit.run.t_stop_s = 10 + m.t_stop_pred_s;
  return fit;
}

HealthBaseline lab_baseline() {
  HealthBaseline b;
  b.c_viscous = cv0;
  b.c_viscous_stderr = 2e-9;
  b.c_coulomb = cc0;
  b.c_coulomb_stderr = 4e-7;
  b.runs = 3;
  b.date = "2024-09-14";
  return b;
}

const HealthFinding* finding(const HealthVerdict& v, std::string_view what) {
  for (const auto& f : v.findings)
    if (f.what == what) return &f;
  return nullptr;
}

std::filesystem::path temp_dir() {
  return std::filesystem::temp_directory_path() / ("spindown_health_" + std::to_string(::getpid()));
}

// Removes the test's files when the tests end.
class TempDirCleanup : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(temp_dir(), ec);
  }
};
const auto* const cleanup = ::testing::AddGlobalTestEnvironment(new TempDirCleanup);

std::string temp_file(const std::string& name, const std::string& text) {
  const auto dir = temp_dir();
  std::filesystem::create_directories(dir);
  const auto path = (dir / name).string();
  std::ofstream(path) << text;
  return path;
}

TEST(MotorHealth, LevelNamesRoundTrip) {
  for (HealthLevel l : {HealthLevel::ok, HealthLevel::check, HealthLevel::service})
    EXPECT_EQ(parse_health_level(health_level_name(l)), l);
  EXPECT_FALSE(parse_health_level("bad"));
}

TEST(MotorHealth, NoReferenceSaysSoInsteadOfInventingOne) {
  const HealthVerdict v = assess_health(combined_fit(cv0, 2e-9, cc0, 4e-7), MotorHealthConfig{});
  EXPECT_FALSE(v.has_reference);
  EXPECT_EQ(v.level, HealthLevel::not_judged);  // never OK when nothing was judged
  EXPECT_EQ(v.reason.rfind("not judged: ", 0), 0u) << v.reason;

  EXPECT_EQ(finding(v, "dry friction"), nullptr);
  // The lab's time rules still apply.
  ASSERT_NE(finding(v, "time to stop"), nullptr);
  EXPECT_NEAR(finding(v, "time to stop")->value, stop_time(cv0, cc0, w0), 1e-9);
}

TEST(MotorHealth, GoodRunAgainstItsBaselineIsOk) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(cv0 * 1.02, 2e-9, cc0 * 0.99, 4e-7), cfg);
  EXPECT_TRUE(v.has_reference);
  EXPECT_EQ(v.level, HealthLevel::ok) << v.reason;
  const HealthFinding* dry = finding(v, "dry friction");
  ASSERT_NE(dry, nullptr);
  EXPECT_NEAR(dry->ratio, 0.99, 1e-9);
  EXPECT_EQ(dry->unit, "N*m");
  EXPECT_GT(dry->ratio_std_error, 0);
  EXPECT_NE(v.reason.find("as expected"), std::string::npos) << v.reason;
}

TEST(MotorHealth, DryFrictionTwoAndAHalfTimesTheBaselineNeedsService) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(cv0, 2e-9, 2.7 * cc0, 5e-7), cfg);
  EXPECT_EQ(v.level, HealthLevel::service) << v.reason;
  EXPECT_NE(v.reason.find("dry friction 2.7× the baseline"), std::string::npos) << v.reason;
  EXPECT_NE(v.reason.find("bearings"), std::string::npos) << v.reason;
  EXPECT_EQ(finding(v, "dry friction")->level, HealthLevel::service);
  EXPECT_EQ(finding(v, "viscous friction")->level, HealthLevel::ok);
  // The stop time is compared too: more friction, sooner stop.
  const HealthFinding* stop = finding(v, "stop time vs baseline");
  ASSERT_NE(stop, nullptr);
  EXPECT_LT(stop->value, stop->reference);
  EXPECT_NE(stop->reason.find("sooner than the baseline predicts"), std::string::npos) << stop->reason;
}

// A doubted run (an rpm file read as volts: friction 1000x any baseline) gets no verdict: its
// numbers are not the motor's friction until the doubt is resolved.
TEST(MotorHealth, ADoubtedRunIsNotJudged) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  RunFit fit = combined_fit(cv0, 2e-9, 1000 * cc0, 5e-7);
  EXPECT_EQ(assess_health(fit, cfg).level, HealthLevel::service);
  fit.doubts = {"readings up to 3364 V: they look like a speed in rpm: try --value-unit rpm"};
  const HealthVerdict v = assess_health(fit, cfg);
  EXPECT_EQ(v.level, HealthLevel::not_judged) << v.reason;
  EXPECT_NE(v.reason.find("doubted"), std::string::npos) << v.reason;
  EXPECT_NE(v.reason.find("try --value-unit rpm"), std::string::npos) << v.reason;
  EXPECT_TRUE(v.findings.empty());
}

TEST(MotorHealth, BetweenThresholdsIsCheck) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(1.9 * cv0, 2e-9, cc0, 4e-7), cfg);
  EXPECT_EQ(v.level, HealthLevel::check) << v.reason;
  EXPECT_NE(v.reason.find("viscous friction 1.9× the baseline"), std::string::npos) << v.reason;
  EXPECT_NE(v.reason.find("lubrication"), std::string::npos) << v.reason;
}

TEST(MotorHealth, ARatioAboveTheThresholdOnlyByNoiseIsNotFlagged) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  // 1.7× but with a 25 % standard error: within 2σ of the check threshold.
  const HealthVerdict noisy = assess_health(combined_fit(cv0, 2e-9, 1.7 * cc0, 0.25 * 1.7 * cc0), cfg);
  EXPECT_EQ(finding(noisy, "dry friction")->level, HealthLevel::ok);
  EXPECT_NE(finding(noisy, "dry friction")->reason.find("within its uncertainty"), std::string::npos);
  // The same ratio measured precisely is flagged.
  const HealthVerdict precise = assess_health(combined_fit(cv0, 2e-9, 1.7 * cc0, 1e-7), cfg);
  EXPECT_EQ(finding(precise, "dry friction")->level, HealthLevel::check);
  // 2.6× with a 10 % error is far from 1: service, though within noise of the threshold.
  const HealthVerdict edge = assess_health(combined_fit(cv0, 2e-9, 2.6 * cc0, 0.1 * 2.6 * cc0), cfg);
  EXPECT_EQ(finding(edge, "dry friction")->level, HealthLevel::service);
  // 1.6× with a 40 % error: past the check threshold, but not distinguishable from 1.
  const HealthVerdict vague = assess_health(combined_fit(cv0, 2e-9, 1.6 * cc0, 0.4 * 1.6 * cc0), cfg);
  EXPECT_EQ(finding(vague, "dry friction")->level, HealthLevel::ok);
  // The baseline's run-to-run spread widens the reference the same way.
  cfg.baseline->c_coulomb_spread = 0.4 * cc0;
  const HealthVerdict spread = assess_health(combined_fit(cv0, 2e-9, 1.7 * cc0, 1e-7), cfg);
  EXPECT_EQ(finding(spread, "dry friction")->level, HealthLevel::ok);
}

TEST(MotorHealth, FarBelowTheBaselineIsACheckToo) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(cv0, 2e-9, 0.3 * cc0, 1e-7), cfg);
  EXPECT_EQ(finding(v, "dry friction")->level, HealthLevel::check);
  EXPECT_NE(v.reason.find("inertia"), std::string::npos) << v.reason;
}

TEST(MotorHealth, ThresholdsComeFromTheConfig) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  cfg.thresholds.check_ratio = 2.0;
  cfg.thresholds.service_ratio = 3.0;
  cfg.thresholds.stop_change_fraction = 0.9;  // the friction ratios alone decide here
  EXPECT_EQ(assess_health(combined_fit(cv0, 2e-9, 2.7 * cc0, 5e-7), cfg).level, HealthLevel::check);
  EXPECT_EQ(assess_health(combined_fit(cv0, 2e-9, 1.8 * cc0, 5e-7), cfg).level, HealthLevel::ok);
  cfg.thresholds.significance_sigma = 0;
  EXPECT_EQ(assess_health(combined_fit(cv0, 2e-9, 3.05 * cc0, 0.3 * cc0), cfg).level, HealthLevel::service);
}

TEST(MotorHealth, DatasheetTorqueIsTorqueConstantTimesNoLoadCurrent) {
  MotorDatasheet ds;
  ds.no_load_current_a = 0.045;
  ds.torque_constant_nm_per_a = 0.00809;
  EXPECT_NEAR(*ds.no_load_friction_torque(), 0.045 * 0.00809, 1e-15);
  // Without a torque constant, k_M = 60/(2π·k_n) from the speed constant (SI: k_M = K_b).
  MotorDatasheet by_speed;
  by_speed.no_load_current_a = 0.045;
  by_speed.speed_constant_rpm_per_v = 1180;
  EXPECT_NEAR(*by_speed.torque_constant(), 60.0 / (2 * std::numbers::pi * 1180), 1e-12);
  MotorDatasheet no_current;
  no_current.torque_constant_nm_per_a = 0.00809;
  EXPECT_FALSE(no_current.no_load_friction_torque());
}

TEST(MotorHealth, FrictionAtNoLoadSpeedAgainstTheDatasheet) {
  MotorDatasheet ds;
  ds.no_load_speed_rpm = 14200;
  ds.torque_constant_nm_per_a = 0.00809;
  const double w_nl = 14200 * 2 * std::numbers::pi / 60;
  const double fitted = cv0 * w_nl + cc0;
  // A datasheet whose k_M·I0 is exactly the fitted torque: ok, ratio 1.
  ds.no_load_current_a = fitted / 0.00809;
  MotorHealthConfig cfg;
  cfg.datasheet = ds;
  const HealthVerdict same = assess_health(combined_fit(cv0, 2e-9, cc0, 4e-7), cfg);
  EXPECT_TRUE(same.has_reference);
  const HealthFinding* t = finding(same, "friction at no-load speed");
  ASSERT_NE(t, nullptr);
  EXPECT_NEAR(t->value, fitted, 1e-12);
  EXPECT_NEAR(t->reference, fitted, 1e-12);
  EXPECT_NEAR(t->std_error, std::hypot(w_nl * 2e-9, 4e-7), 1e-12);  // propagated from the fit's errors
  EXPECT_EQ(same.level, HealthLevel::ok) << same.reason;

  // A datasheet allowing 1/1.8 of it: the motor stops ~44 % sooner than the datasheet predicts.
  cfg.datasheet->no_load_current_a = fitted / 1.8 / 0.00809;
  const HealthVerdict worse = assess_health(combined_fit(cv0, 2e-9, cc0, 4e-7), cfg);
  EXPECT_EQ(worse.level, HealthLevel::check) << worse.reason;
  EXPECT_NE(worse.reason.find("stops 44 % sooner than the datasheet predicts"), std::string::npos) << worse.reason;
  const HealthFinding* stop = finding(worse, "stop time vs datasheet");
  ASSERT_NE(stop, nullptr);
  EXPECT_NEAR(stop->reference / stop->value, 1.8, 1e-9);
}

TEST(MotorHealth, RotorInertiaAboveTheBenchsJIsFlagged) {
  MotorHealthConfig cfg;
  cfg.datasheet = MotorDatasheet{};
  cfg.datasheet->rotor_inertia_kg_m2 = 2 * J;
  const HealthVerdict v = assess_health(combined_fit(cv0, 2e-9, cc0, 4e-7), cfg);
  EXPECT_EQ(v.level, HealthLevel::check);
  EXPECT_NE(v.reason.find("rotor"), std::string::npos) << v.reason;
}

TEST(MotorHealth, LabRulesTooLongToSlowDownAndToStop) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const RunFit fit = combined_fit(cv0, 2e-9, cc0, 4e-7);
  const double t_stop = stop_time(cv0, cc0, w0);  // ≈ 27 s
  EXPECT_EQ(assess_health(fit, cfg).level, HealthLevel::ok);
  cfg.thresholds.max_stop_s = 20;
  HealthVerdict v = assess_health(fit, cfg);
  EXPECT_EQ(v.level, HealthLevel::check);
  EXPECT_NE(v.reason.find("too long to stop"), std::string::npos) << v.reason;
  EXPECT_NEAR(finding(v, "time to stop")->value, t_stop, 1e-9);
  cfg.thresholds.max_stop_s = 60;
  cfg.thresholds.max_slowdown_s = 5;
  v = assess_health(fit, cfg);
  EXPECT_EQ(v.level, HealthLevel::check);
  EXPECT_NE(v.reason.find("too long to slow down"), std::string::npos) << v.reason;
  // Half the speed: J/c_v·ln((w0 + k)/(w0/2 + k)) with k = c_c/c_v.
  const double k = cc0 / cv0;
  EXPECT_NEAR(finding(v, "time to slow down")->value, J / cv0 * std::log((w0 + k) / (w0 / 2 + k)), 1e-9);
}

TEST(MotorHealth, UnconvergedFitIsACheckNotAnOk) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  RunFit fit = combined_fit(cv0, 2e-9, cc0, 4e-7);
  fit.models[0].converged = false;
  fit.best.clear();
  const HealthVerdict v = assess_health(fit, cfg);
  EXPECT_EQ(v.level, HealthLevel::check);
  EXPECT_NE(v.reason.find("no model converged"), std::string::npos) << v.reason;
}

TEST(MotorHealthConfig, ReadsEverySection) {
  const auto path = temp_file("bench-7.toml", R"(bench_id = "bench-7"
[serial]
device = "/dev/ttyACM0"
[motor]
speed_constant_rpm_per_v = 1180
no_load_speed_rpm = 14200
no_load_current_a = 0.045
rotor_inertia_kg_m2 = 1.09e-6
[baseline]
c_viscous_n_m_s = 1.8e-7
c_viscous_stderr = 2e-9
c_coulomb_n_m = 1.14e-4
c_coulomb_stderr = 4e-7
runs = 3
date = 2024-09-14
[health]
service_ratio = 3
max_stop_s = 45
)");
  const MotorHealthConfig cfg = load_motor_health_config(path);
  ASSERT_TRUE(cfg.datasheet);
  EXPECT_DOUBLE_EQ(*cfg.datasheet->no_load_current_a, 0.045);
  EXPECT_FALSE(cfg.datasheet->torque_constant_nm_per_a);
  EXPECT_TRUE(cfg.datasheet->no_load_friction_torque());
  ASSERT_TRUE(cfg.baseline);
  EXPECT_DOUBLE_EQ(cfg.baseline->c_coulomb, 1.14e-4);
  EXPECT_EQ(cfg.baseline->runs, 3);
  EXPECT_EQ(cfg.baseline->date, "2024-09-14");
  EXPECT_DOUBLE_EQ(cfg.thresholds.service_ratio, 3);
  EXPECT_DOUBLE_EQ(cfg.thresholds.check_ratio, 1.5);  // default kept
  EXPECT_DOUBLE_EQ(cfg.thresholds.max_stop_s, 45);
  EXPECT_EQ(bench_id_of_config(path), "bench-7");
  const BenchFile bf = load_bench_file(path);
  EXPECT_EQ(bf.bench, "bench-7");
  EXPECT_FALSE(bf.sets_inertia);
}

TEST(MotorHealthConfig, NoHealthSectionsMeansNoReference) {
  const auto path = temp_file("bench-8.toml", "[serial]\ndevice = \"/dev/ttyACM0\"\n");
  const MotorHealthConfig cfg = load_motor_health_config(path);
  EXPECT_FALSE(cfg.datasheet);
  EXPECT_FALSE(cfg.baseline);
  EXPECT_EQ(bench_id_of_config(path), "bench-8");  // from the file name
}

void expect_error(const std::string& text, const std::string& key_words) {
  const auto path = temp_file("bad.toml", text);
  try {
    load_motor_health_config(path);
    ADD_FAILURE() << "no error for: " << text;
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find(key_words), std::string::npos) << what;
  }
}

TEST(MotorHealthConfig, BadFilesNameFileAndKey) {
  expect_error("[motor]\nno_load_current_a = \"45 mA\"\n", "key 'motor.no_load_current_a': is not a number");
  expect_error("[motor]\nno_load_current_a = -0.045\n", "key 'motor.no_load_current_a': must be positive");
  expect_error("[motor]\nno_load_current = 0.045\n", "key 'motor.no_load_current': unknown key");
  expect_error("[motor]\nno_load_current_a = 0.045\n", "needs torque_constant_nm_per_a or speed_constant");
  expect_error("[baseline]\nc_viscous_n_m_s = 1e-7\n", "key 'baseline.c_coulomb_n_m': missing");
  expect_error("[baseline]\nc_viscous_n_m_s = 1e-7\nc_coulomb_n_m = 1e-4\nruns = 0\n", "key 'baseline.runs'");
  expect_error("[health]\ncheck_ratio = 3\nservice_ratio = 2\n", "service_ratio 2 must be at least check_ratio 3");
  expect_error("[health]\nmax_stop_s = \"a minute\"\n", "key 'health.max_stop_s'");
  expect_error("[motor\nno_load_current_a = 1\n", ":1:");  // parse error: file:line:column
  EXPECT_THROW(load_motor_health_config("/nonexistent/bench.toml"), std::runtime_error);
}

TEST(MotorHealthConfig, ExampleBenchFileDocumentsEveryKeyAndLoads) {
  const std::string path = std::string(SPINDOWN_SOURCE_DIR) + "/deploy/benches/example.toml";
  const BenchFile f = load_bench_file(path);
  EXPECT_EQ(f.bench, "example");
  EXPECT_TRUE(f.sets_inertia);
  EXPECT_TRUE(f.sets_kb);
  ASSERT_TRUE(f.health.datasheet);
  EXPECT_TRUE(f.health.datasheet->no_load_friction_torque());
  std::ifstream in(path);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const char* key : {"check_ratio", "service_ratio", "significance_sigma", "max_slowdown_s", "slowdown_fraction",
                          "max_stop_s", "c_viscous_n_m_s", "c_viscous_stderr", "c_viscous_spread", "c_coulomb_n_m",
                          "c_coulomb_stderr", "c_coulomb_spread", "runs", "date", "no_load_speed_rpm",
                          "no_load_current_a", "torque_constant_nm_per_a", "rotor_inertia_kg_m2",
                          "speed_constant_rpm_per_v"})
    EXPECT_NE(text.find(key), std::string::npos) << key;
}

TEST(HealthBaseline, WeightedMeanOfGoodRuns) {
  std::vector<BaselineRun> runs = {{"a", 1.0e-7, 1e-9, 1.0e-4, 1e-6, J, 344}, {"b", 1.2e-7, 2e-9, 1.1e-4, 1e-6, J, 348}};
  const auto b = make_baseline(runs, "2024-09-14", "test");
  ASSERT_TRUE(b);
  EXPECT_NEAR(b->omega0, 346, 1e-9);
  EXPECT_NEAR(b->omega0_spread, std::sqrt(8.0), 1e-9);
  EXPECT_NEAR(b->c_coulomb, 1.05e-4, 1e-12);
  // Inverse-variance weights 4:1 for c_v.
  EXPECT_NEAR(b->c_viscous, (4 * 1.0e-7 + 1.2e-7) / 5, 1e-15);
  EXPECT_EQ(b->runs, 2);
  EXPECT_NEAR(b->c_coulomb_spread, std::sqrt(2) * 0.05e-4, 1e-12);
  // The runs disagree by far more than their errors: the standard error is widened (Birge).
  EXPECT_GT(b->c_coulomb_stderr, 1e-6 / std::sqrt(2));
  std::string why;
  EXPECT_FALSE(make_baseline({}, "", "", &why));
  EXPECT_NE(why.find("no good run"), std::string::npos);
}

TEST(HealthBaseline, SectionIsReplacedInPlaceKeepingEverythingElse) {
  const std::string original = R"(# bench 3, room 101
bench_id = "bench-3"   # the one by the window

[serial]
device = "/dev/ttyACM0"

[baseline]
# old one
c_viscous_n_m_s = 1e-7
c_coulomb_n_m = 1e-4

# thresholds agreed with the lab
[health]
check_ratio = 1.6
)";
  HealthBaseline b = lab_baseline();
  b.omega0 = 346.0;  // the runs' speed at the cut, written and read back
  b.omega0_spread = 1.5;
  std::string why;
  const auto updated = with_baseline_section(original, b, &why);
  ASSERT_TRUE(updated) << why;
  EXPECT_NE(updated->find("# bench 3, room 101"), std::string::npos);
  EXPECT_NE(updated->find("# the one by the window"), std::string::npos);
  EXPECT_NE(updated->find("# thresholds agreed with the lab\n[health]"), std::string::npos) << *updated;
  EXPECT_EQ(updated->find("# old one"), std::string::npos);
  const auto path = temp_file("updated.toml", *updated);
  const MotorHealthConfig cfg = load_motor_health_config(path);
  ASSERT_TRUE(cfg.baseline);
  EXPECT_DOUBLE_EQ(cfg.baseline->c_coulomb, cc0);
  EXPECT_DOUBLE_EQ(cfg.baseline->c_viscous_stderr, 2e-9);
  EXPECT_EQ(cfg.baseline->date, "2024-09-14");
  EXPECT_DOUBLE_EQ(cfg.baseline->omega0, 346.0);
  EXPECT_DOUBLE_EQ(cfg.baseline->omega0_spread, 1.5);
  EXPECT_DOUBLE_EQ(cfg.thresholds.check_ratio, 1.6);

  // No [baseline] yet: appended.
  const auto appended = with_baseline_section("bench_id = \"x\"\n", b, &why);
  ASSERT_TRUE(appended) << why;
  EXPECT_EQ(appended->rfind("bench_id = \"x\"\n", 0), 0u);
  EXPECT_NE(appended->find("[baseline]"), std::string::npos);
  // A baseline as dotted keys cannot be replaced cleanly: refused with a reason.
  EXPECT_FALSE(with_baseline_section("baseline.c_coulomb_n_m = 1e-4\n", b, &why));
  EXPECT_NE(why.find("dotted"), std::string::npos) << why;
}

// End to end on simulated runs: a baseline from good runs, then a run with 3× the Coulomb
// friction needs service (past the 2.5× threshold by more than its error) and another good run is ok.
TEST(MotorHealth, FittedRunsAgainstABaselineFromGoodRuns) {
  auto fitted = [](double coulomb, std::uint64_t seed) {
    SyntheticRunSpec spec;
    spec.friction.coulomb = coulomb;
    spec.seed = seed;
    const SyntheticRun run = make_synthetic_run(spec);
    Recording rec;
    for (std::size_t i = 0; i < run.t_ms.size(); ++i) rec.push(run.t_ms[i] / 1000.0, run.volts[i]);
    const Segmentation seg = find_runs(rec);
    EXPECT_EQ(seg.runs.size(), 1u);
    return fit_run(rec, seg.runs.at(0), FitOptions{});
  };
  std::vector<BaselineRun> good;
  for (std::uint64_t seed : {1, 2, 3}) {
    std::string why;
    auto r = baseline_run(fitted(cc0, seed), "good", &why);
    ASSERT_TRUE(r) << why;
    good.push_back(*r);
  }
  MotorHealthConfig cfg;
  cfg.baseline = make_baseline(good, "2024-09-14", "test");
  ASSERT_TRUE(cfg.baseline);
  EXPECT_NEAR(cfg.baseline->c_coulomb / cc0, 1.0, 0.05);

  const HealthVerdict worn = assess_health(fitted(3.0 * cc0, 7), cfg);
  EXPECT_EQ(worn.level, HealthLevel::service) << worn.reason;
  EXPECT_NE(worn.reason.find("dry friction 3."), std::string::npos) << worn.reason;
  const HealthVerdict fine = assess_health(fitted(cc0, 8), cfg);
  EXPECT_EQ(fine.level, HealthLevel::ok) << fine.reason;
}

}  // namespace

// A worn motor whose friction ratios stay below check_ratio still stops much sooner than the
// baseline predicts: that is a check, never OK.
TEST(MotorHealth, StoppingMuchSoonerThanTheBaselineIsACheck) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  cfg.thresholds.significance_sigma = 1e9;  // no friction ratio is ever flagged
  const HealthVerdict v = assess_health(combined_fit(1.3 * cv0, 2e-9, 1.45 * cc0, 5e-7), cfg);
  const HealthFinding* stop = finding(v, "stop time vs baseline");
  ASSERT_NE(stop, nullptr);
  EXPECT_LT(stop->ratio, 0.75);
  EXPECT_EQ(stop->level, HealthLevel::check);
  EXPECT_EQ(v.level, HealthLevel::check);
  EXPECT_NE(v.reason.find("sooner than the baseline"), std::string::npos) << v.reason;
  // The same motor as the baseline: within a few per cent, no flag.
  EXPECT_EQ(assess_health(combined_fit(cv0, 2e-9, cc0, 5e-7), cfg).level, HealthLevel::ok);
}

namespace {
BaselineRun baseline_of(double cv, double cc, std::string source) {
  return BaselineRun{std::move(source), cv, 0.006e-7, cc, 0.001e-4, J};
}
}  // namespace

TEST(HealthBaseline, AWornRunIsSetAsideNamedAndLeftOutOfTheMean) {
  const std::vector<BaselineRun> runs = {baseline_of(1.822e-7, 1.1389e-4, "a run 1"),
                                         baseline_of(1.823e-7, 1.1386e-4, "b run 1"),
                                         baseline_of(1.817e-7, 1.1396e-4, "c run 1"),
                                         baseline_of(1.78e-7, 4.51e-4, "worn run 1")};
  std::vector<SetAsideRun> aside;
  std::string why;
  const auto b = make_baseline(runs, "2026-11-26", "test", &why, &aside);
  ASSERT_TRUE(b) << why;
  ASSERT_EQ(aside.size(), 1u);
  EXPECT_EQ(aside[0].source, "worn run 1");
  EXPECT_NE(aside[0].why.find("dry friction 4"), std::string::npos) << aside[0].why;
  EXPECT_EQ(b->runs, 3);
  EXPECT_NEAR(b->c_coulomb, 1.139e-4, 0.001e-4);  // the worn run's 4.5e-4 is not in the mean
  // Its error includes the run-to-run scatter: never below spread/sqrt(n).
  EXPECT_GE(b->c_coulomb_stderr, b->c_coulomb_spread / std::sqrt(3.0) * (1 - 1e-12));
}

TEST(HealthBaseline, TwoRunsThatDisagreeAreRefusedNotAveraged) {
  const std::vector<BaselineRun> runs = {baseline_of(1.822e-7, 1.1389e-4, "good run 1"),
                                         baseline_of(1.78e-7, 4.51e-4, "worn run 1")};
  std::string why;
  EXPECT_FALSE(make_baseline(runs, "2026-11-26", "test", &why));
  EXPECT_NE(why.find("which one is the motor's normal cannot be told"), std::string::npos) << why;
  // Two runs of one motor a few per cent apart (far beyond their tiny errors) are its scatter.
  const std::vector<BaselineRun> close = {baseline_of(1.822e-7, 1.1389e-4, "a"), baseline_of(1.85e-7, 1.16e-4, "b")};
  EXPECT_TRUE(make_baseline(close, "2026-11-26", "test", &why)) << why;
}

TEST(HealthBaseline, RunsThatNeverStoppedOrWerePartialAreNotUsed) {
  RunFit fit = combined_fit(cv0, 2e-9, cc0, 4e-7);
  std::string why;
  EXPECT_TRUE(baseline_run(fit, "ok", &why)) << why;
  fit.run.stopped = false;
  fit.run.end = Run::End::end_of_data;
  EXPECT_FALSE(baseline_run(fit, "cut short", &why));
  EXPECT_NE(why.find("never stopped"), std::string::npos) << why;
  fit.run.stopped = true;
  fit.run.lead_in = "none";
  EXPECT_FALSE(baseline_run(fit, "partial", &why));
  EXPECT_NE(why.find("partial"), std::string::npos) << why;
}

}  // namespace spindown

namespace spindown {
namespace {

// A load across the motor's leads (left on a switched-off driver; a meter's shunt): viscous
// friction far up and dry friction *down* (the terminal voltage divided). Electrical braking is
// named first, before grease; with dry friction as it was, viscous up stays "lubrication".
TEST(MotorHealth, ViscousUpWithDryDownIsElectricalBrakingNotGrease) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(7.4 * cv0, 2e-8, 0.83 * cc0, 5e-7), cfg);
  EXPECT_EQ(v.level, HealthLevel::service) << v.reason;
  const auto leads = v.reason.find("leads are disconnected"), grease = v.reason.find("lubrication");
  ASSERT_NE(leads, std::string::npos) << v.reason;
  EXPECT_NE(v.reason.find("electrical braking"), std::string::npos) << v.reason;
  EXPECT_TRUE(grease == std::string::npos || leads < grease) << v.reason;
  const HealthVerdict g = assess_health(combined_fit(3.0 * cv0, 2e-8, 1.0 * cc0, 5e-7), cfg);
  EXPECT_EQ(g.reason.find("electrical braking"), std::string::npos) << g.reason;
  EXPECT_NE(g.reason.find("lubrication"), std::string::npos) << g.reason;
}

}  // namespace
}  // namespace spindown

namespace spindown {
namespace {

// A scope's sample index followed as milliseconds of a 20-ms period: c3 and c4 both exactly 20x
// the baseline. Not judged (no SERVICE on a healthy motor), and the time unit is named; J wrong
// (0.37x both) is no round factor and stays judged.
TEST(MotorHealth, BothFrictionsTheSameRoundMultipleIsATimeUnitNotWear) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  const HealthVerdict v = assess_health(combined_fit(20 * cv0, 2e-8, 20 * cc0, 5e-6), cfg);
  EXPECT_EQ(v.level, HealthLevel::not_judged) << v.reason;
  EXPECT_NE(v.reason.find("time unit"), std::string::npos) << v.reason;
  const HealthVerdict j = assess_health(combined_fit(0.37 * cv0, 2e-9, 0.37 * cc0, 4e-7), cfg);
  EXPECT_NE(j.level, HealthLevel::not_judged) << j.reason;
}

}  // namespace
}  // namespace spindown

namespace spindown {
namespace {

// A 3.3 V board running the lab's sketch written for 5 V: every reading 1.52x the back-EMF. Dry
// friction reads 1.52x, viscous friction as it was, and the speed at the cut 1.52x what the same
// supply gave the baseline runs: the reading's scale is named, not bearings. The same dry friction
// at the baseline's speed (a worn bearing) stays "bearings".
TEST(MotorHealth, DryFrictionAndTheCutSpeedScaledAlikeIsTheReadingsScale) {
  MotorHealthConfig cfg;
  cfg.baseline = lab_baseline();
  cfg.baseline->omega0 = w0;
  cfg.baseline->omega0_spread = 2.0;
  const HealthVerdict v = assess_health(combined_fit(cv0, 2e-9, 1.52 * cc0, 5e-7, 1.52 * w0), cfg);
  EXPECT_NE(v.reason.find("the reading's scale"), std::string::npos) << v.reason;
  const auto scale = v.reason.find("the reading's scale"), bearings = v.reason.find("bearings");
  EXPECT_TRUE(bearings == std::string::npos || scale < bearings) << v.reason;
  const HealthVerdict worn = assess_health(combined_fit(cv0, 2e-9, 1.52 * cc0, 5e-7, w0), cfg);
  EXPECT_EQ(worn.reason.find("the reading's scale"), std::string::npos) << worn.reason;
  EXPECT_NE(worn.reason.find("bearings"), std::string::npos) << worn.reason;
}

}  // namespace
}  // namespace spindown
