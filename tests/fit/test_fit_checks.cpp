// What a fit cannot say by itself (fit_checks.hpp): implausible units, an extra friction term the
// print cannot resolve, a best model that misses; and what the fit report holds beside the values
// (correlations, reduced χ²). Each case is a generated run with a known truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "spindown/fit.hpp"
#include "spindown/fit_checks.hpp"
#include "synthetic_case.hpp"

using namespace spindown;
using spindown::testing::Case;
using spindown::testing::make_case;

namespace {

RunFit fit_of(const Case& c, const std::vector<double>& values, Quantity q = Quantity::back_emf_volts) {
  FitOptions opt;
  opt.bench = c.spec.bench;
  return fit_run(c.t, values, q, c.seg, opt);
}

bool mentions(const std::vector<std::string>& doubts, const std::string& words) {
  return std::any_of(doubts.begin(), doubts.end(), [&](const std::string& d) { return d.find(words) != std::string::npos; });
}

}  // namespace

TEST(FitChecks, TheLabsRunIsNotDoubted) {
  const Case c = make_case(SyntheticRunSpec{});
  const RunFit f = fit_of(c, c.run.volts);
  EXPECT_EQ(f.best, "combined");
  EXPECT_TRUE(f.doubts.empty()) << f.doubts.front();
  EXPECT_NEAR(f.reading_step, 0.01, 1e-9);  // two decimals
}

TEST(FitChecks, ATachometerInRpmReadAsVoltsIsDoubtedWithTheFix) {
  const Case c = make_case(SyntheticRunSpec{});
  std::vector<double> rpm;
  for (double v : c.run.volts) rpm.push_back(std::round(v * 1180));  // a tachometer's rpm, no header
  const RunFit f = fit_of(c, rpm);
  ASSERT_FALSE(f.doubts.empty());
  EXPECT_TRUE(mentions(f.doubts, "try --value-unit rpm")) << f.doubts.front();
  // Read as what it is, the same run is believed.
  EXPECT_TRUE(fit_of(c, rpm, Quantity::rpm).doubts.empty());
}

// The handout's sketch with its "* 5.0 / 1023" left out prints analogRead()'s counts ("574.00"):
// whole numbers up to 1023 are doubted as counts and the fix proposed is --value-unit counts (the
// rpm reading, followed, gave c4 5.8x too small); read as counts x 5/1023 V, the run is believed.
TEST(FitChecks, RawAnalogReadCountsAreDoubtedAsCounts) {
  const Case c = make_case(SyntheticRunSpec{});
  std::vector<double> counts, volts;
  for (double v : c.run.volts) counts.push_back(std::round(v / 5.0 * 1023));
  for (double n : counts) volts.push_back(n * 5.0 / 1023);
  const RunFit f = fit_of(c, counts);
  ASSERT_FALSE(f.doubts.empty());
  EXPECT_TRUE(mentions(f.doubts, "try --value-unit counts")) << f.doubts.front();
  EXPECT_FALSE(mentions(f.doubts, "--value-unit rpm")) << f.doubts.front();
  EXPECT_TRUE(fit_of(c, volts).doubts.empty());
}

// Issue 32 (a vehicle's km/h in a headerless file): readings of a few tens, read as volts by
// default, give a speed far beyond a flywheel's; the doubt says they were taken as volts.
TEST(FitChecks, ASpeedReadAsVoltsSaysTheReadingsWereTakenAsVolts) {
  const Case c = make_case(SyntheticRunSpec{});
  std::vector<double> kmh;
  for (double v : c.run.volts) kmh.push_back(v * 9.5);  // up to ~27: below the volts limit, above any flywheel
  const RunFit f = fit_of(c, kmh);
  ASSERT_TRUE(mentions(f.doubts, "faster than a teaching flywheel")) << (f.doubts.empty() ? "" : f.doubts.front());
  EXPECT_TRUE(mentions(f.doubts, "the readings were taken as back-EMF in volts")) << f.doubts.front();
  EXPECT_TRUE(mentions(f.doubts, "--value-unit")) << f.doubts.front();
}

TEST(FitChecks, VoltsReadAsRpmAreDoubtedToo) {
  const Case c = make_case(SyntheticRunSpec{});
  const RunFit f = fit_of(c, c.run.volts, Quantity::rpm);
  EXPECT_TRUE(mentions(f.doubts, "try --value-unit V")) << (f.doubts.empty() ? "" : f.doubts.front());
}

TEST(FitChecks, AViscousMotorIsNotCalledCombinedOnWhatThePrintCannotResolve) {
  // data/viscous-only.tsv's motor (c_v 1.2e-6, no Coulomb friction), over several noise draws:
  // by BIC alone a continuous-noise likelihood calls some of them "combined", because the 2-decimal
  // print makes the slow tail a staircase; the resolution check keeps viscous for every one.
  int rescued = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SyntheticRunSpec spec;
    spec.friction = {1.2e-6, 0};
    spec.max_coast_s = 120;
    spec.seed = seed;
    const Case c = make_case(spec);
    const RunFit f = fit_of(c, c.run.volts);
    EXPECT_EQ(f.best, "viscous") << "seed " << seed << ": " << f.best_reason;
    rescued += f.best_reason.find("cannot tell them apart") != std::string::npos;
  }
  EXPECT_GT(rescued, 0);  // the check did the work at least once (BIC alone would have said combined)
}

// A viscous motor read by a converter that truncates (every reading half a step low: within the
// ATmega's ±2 LSB) on a print fine enough to resolve it: by BIC combined wins by thousands, its dry
// friction being the offset; kept viscous, said as such. A real dry friction (the lab's motor) is
// far beyond any offset and still wins.
TEST(FitChecks, ACoulombTermASensorOffsetImitatesDoesNotDecideTheModel) {
  SyntheticRunSpec spec;
  spec.friction = {1.2e-6, 0};
  spec.max_coast_s = 40;
  spec.noise_v = 0.0005;
  spec.decimals = 4;
  spec.seed = 3;
  const Case c = make_case(spec);
  std::vector<double> low;
  for (double v : c.run.volts) low.push_back(v > 0 ? v - 0.0024 : v);  // half of a 10-bit step at 5 V
  const RunFit f = fit_of(c, low);
  EXPECT_EQ(f.best, "viscous") << f.best_reason;
  EXPECT_NE(f.best_reason.find("cannot tell dry friction from a zero level"), std::string::npos) << f.best_reason;
  EXPECT_EQ(fit_of(make_case(SyntheticRunSpec{}), make_case(SyntheticRunSpec{}).run.volts).best, "combined");
}

TEST(FitChecks, AStribeckRunSaysTheModelMissesAndPointsToExplain) {
  SyntheticRunSpec spec;
  spec.friction.stribeck_static = 2.5e-4;
  spec.friction.stribeck_speed = 60;
  const Case c = make_case(spec);
  const RunFit f = fit_of(c, c.run.volts);
  EXPECT_TRUE(mentions(f.doubts, "model misses")) << (f.doubts.empty() ? "no doubt" : f.doubts.front());
  EXPECT_TRUE(mentions(f.doubts, "spindown explain"));
}

// A windage torque of 3 % of the friction at the cut: a few stretches of 25 readings show it
// beyond 4 standard errors, all of them together clearly, and it moves c3 by ~8 %, tens of its
// ±: doubted. The same term 3,000 times smaller moves nothing and is not. (Quantization off and
// fine noise, so that the misfit is the model's.)
TEST(FitChecks, AMisfitTheStretchesShowTogetherIsDoubtedAndANegligibleOneIsNot) {
  auto run_with_windage = [](double fraction) {
    SyntheticRunSpec spec;
    spec.adc_bits = 0;
    spec.decimals = -1;
    spec.noise_v = 0.001;
    const double omega0 = spec.e0_v / spec.bench.kb_v_s_per_rad;
    spec.friction.windage = fraction * spec.friction.torque(omega0) / (omega0 * omega0);
    const Case c = make_case(spec);
    return fit_of(c, c.run.volts);
  };
  const RunFit three_percent = run_with_windage(0.03);  // c3 +8 %, c4 -1 %
  EXPECT_TRUE(mentions(three_percent.doubts, "model misses")) << "3 % windage not doubted";
  EXPECT_TRUE(mentions(three_percent.doubts, "beyond their ±"));
  const RunFit negligible = run_with_windage(1e-5);
  EXPECT_TRUE(negligible.doubts.empty()) << negligible.doubts.front();
}

// A coast of ~90 readings that a brake cuts short half-way: under 200 samples, so the misfit
// test's bins follow the run's length (here ~11 readings each) and the gross misfit is said.
TEST(FitChecks, AShortCoastThatTheModelGrosslyMissesIsDoubted) {
  SyntheticRunSpec spec;
  spec.friction.stribeck_static = 8e-4;  // a hard extra drag at low speed: the coast ends abruptly
  spec.friction.stribeck_speed = 150;
  spec.friction.coulomb = 3e-4;
  spec.e0_v = 1.2;
  spec.noise_v = 0.002;
  const Case c = make_case(spec);
  const RunFit f = fit_of(c, c.run.volts);
  ASSERT_LT(c.run.t_stop_s / spec.period_s, 200) << "the coast is meant to be short";
  EXPECT_TRUE(mentions(f.doubts, "model misses")) << (f.doubts.empty() ? "no doubt" : f.doubts.front());
}

TEST(FitChecks, CorrelationsAndReducedChiSquare) {
  const Case c = make_case(SyntheticRunSpec{});
  const RunFit f = fit_of(c, c.run.volts);
  const ModelFit* m = f.model(ModelKind::combined);
  ASSERT_NE(m, nullptr);
  ASSERT_EQ(m->correlated, (std::vector<std::string>{"omega0", "c3", "c4"}));
  ASSERT_EQ(m->correlation.size(), 9u);
  EXPECT_LT(m->correlation[1 * 3 + 2], -0.8);  // c3 and c4 trade off against each other
  EXPECT_EQ(m->correlation[1 * 3 + 2], m->correlation[2 * 3 + 1]);
  EXPECT_EQ(m->correlation[0], 1.0);
  // Against the run's own noise model the right model's χ² per degree of freedom is of order 1;
  // the viscous model, which misses, is far above it.
  EXPECT_GT(m->reduced_chi2, 0.1);
  EXPECT_LT(m->reduced_chi2, 3.0);
  EXPECT_GT(f.model(ModelKind::viscous)->reduced_chi2, 50.0);
}

TEST(FitChecks, ReadingStep) {
  EXPECT_NEAR(reading_step(std::vector<double>{0, 0.01, 0.03, 0.04, 0.07, 0.1, 0.12, 0.2, 0.21}), 0.01, 1e-12);
  EXPECT_EQ(reading_step(std::vector<double>{0.1234, 0.52, 0.9871, 1.3, 1.77, 2.01, 2.333, 2.9, 3.1}), 0.0);
}

// J (geometry) and K_b (datasheet) are not exact: their uncertainty goes into each coefficient as
// c scales with them, beside the statistical error.
TEST(FitChecks, UncertaintyOfJAndKbIsCarriedIntoTheCoefficients) {
  SyntheticRunSpec spec;
  spec.bench.inertia_rel_error = 0.02;
  spec.bench.kb_rel_error = 0.01;
  const Case c = make_case(spec);
  const RunFit f = fit_of(c, c.run.volts);
  const ModelFit* m = f.model(ModelKind::combined);
  ASSERT_NE(m, nullptr);
  EXPECT_DOUBLE_EQ(m->param("c3")->bench_error, 0.02 * m->param("c3")->value);              // c3 = α·J
  EXPECT_DOUBLE_EQ(m->param("c4")->bench_error, std::hypot(0.02, 0.01) * m->param("c4")->value);  // β·J/K_b
  EXPECT_DOUBLE_EQ(m->param("omega0")->bench_error, 0.01 * m->param("omega0")->value);      // u0/K_b
  EXPECT_EQ(m->param("A")->bench_error, 0.0);
  // A speed reading needs no K_b: only J's part remains.
  std::vector<double> rad_s;
  for (double v : c.run.volts) rad_s.push_back(v / spec.bench.kb_v_s_per_rad);
  const RunFit speed = fit_of(c, rad_s, Quantity::rad_per_s);
  const ModelFit* s = speed.model(ModelKind::combined);
  ASSERT_NE(s, nullptr);
  EXPECT_DOUBLE_EQ(s->param("c4")->bench_error, 0.02 * s->param("c4")->value);
  EXPECT_EQ(s->param("omega0")->bench_error, 0.0);
  // Exact J and K_b (the default): nothing added.
  EXPECT_EQ(fit_of(make_case(SyntheticRunSpec{}), c.run.volts).model(ModelKind::combined)->param("c3")->bench_error, 0.0);
}

// Whole numbers in the thousands read as volts: a speed in rpm, or whole millivolts (a sketch
// printing analogRead(A0) * 5000L / 1023): both are proposed, the user knows which.
TEST(FitChecks, WholeNumbersInTheThousandsProposeRpmOrMillivolts) {
  RunFit fit;
  fit.quantity = Quantity::back_emf_volts;
  fit.bench.kb_v_s_per_rad = 0.00809262;
  const auto d = unit_doubts(fit, 3216.0, true);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NE(d[0].find("--value-unit rpm"), std::string::npos) << d[0];
  EXPECT_NE(d[0].find("--value-unit mV if they are millivolts"), std::string::npos) << d[0];
  const auto f = unit_doubts(fit, 3216.5, false);  // fractions: no whole millivolts
  ASSERT_EQ(f.size(), 1u);
  EXPECT_EQ(f[0].find("mV if"), std::string::npos) << f[0];
}
