// lead_in: what came before a cut, named by comparing it with the coast in the coast's own noise,
// on its own.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <random>
#include <string>

#include "spindown/lead_in.hpp"
#include "recorded_readings.hpp"

using namespace spindown;
using spindown::test::at;
using spindown::test::record;

namespace {

// The lead-in [0, cut_s) of s described and named, the coast after it starting at v0 and falling
// `slope` a second with scatter sd_post.
std::string name_lead_in(const SampleStore& s, double cut_s, double v0, double slope, double sd_post, CutSplit* out = nullptr) {
  CutSplit sp;
  sp.a = 0;
  sp.cut_index = sp.pre_end = at(cut_s);
  sp.v0 = v0;
  sp.post_slope = slope;
  sp.sd_post = sd_post;
  sp.post_rough = sd_post;
  describe_lead_in(s, sp);
  if (out) *out = sp;
  return classify_lead_in(sp);
}

}  // namespace

TEST(LeadIn, TheSuppliesVoltageThenTheBackEmfIsASupplyLeadIn) {
  // 3.30 V of the supply across the motor, then the back-EMF at 2.70 V falling.
  const SampleStore s = record([](double t) { return t < 2 ? 3.3 : 2.7 - 0.1 * (t - 2); }, 4.0, 0.004, 0.0, 21);
  CutSplit sp;
  EXPECT_EQ(name_lead_in(s, 2.0, 2.7, -0.1, 0.004, &sp), "supply");
  EXPECT_NEAR(sp.pre_mean, 3.3, 0.005);
  EXPECT_TRUE(sp.pre_flat);  // its slope shown well below the coast's
  EXPECT_FALSE(sp.pre_declining);
}

TEST(LeadIn, ZerosUntilTheMotorWasConnectedIsAZerosLeadIn) {
  const SampleStore s = record([](double t) { return t < 2 ? 0.0 : 2.7 - 0.1 * (t - 2); }, 4.0, 0.004, 0.0, 22);
  EXPECT_EQ(name_lead_in(s, 2.0, 2.7, -0.1, 0.004), "zeros");
}

TEST(LeadIn, ASpeedReadingRunningOnIntoTheCoastIsPowered) {
  // A tachometer's 1500 rpm held by the drive, then the coast from the same speed: no step.
  const SampleStore s = record([](double t) { return t < 2 ? 1500.0 : 1500.0 - 40.0 * (t - 2); }, 4.0, 2.0, 0.0, 23);
  EXPECT_EQ(name_lead_in(s, 2.0, 1500.0, -40.0, 2.0), "powered");
}

TEST(LeadIn, AnOpenPinsHumIsFloatingWhateverItsLevel) {
  // A0 open: mains hum ±0.4 V about 1.5 V; sampled at 50 Hz a 61.7 Hz pick-up shows as 11.7 Hz,
  // far rougher from sample to sample than the coast.
  const SampleStore s = record([](double t) { return t < 2 ? 1.5 + 0.4 * std::sin(2 * M_PI * 61.7 * t) : 2.7 - 0.1 * (t - 2); },
                               4.0, 0.004, 0.0, 24);
  CutSplit sp;
  EXPECT_EQ(name_lead_in(s, 2.0, 2.7, -0.1, 0.004, &sp), "floating");
  EXPECT_GT(sp.pre_rough, 10 * 0.004);
  // Hum at 49.3 Hz shows as a slow 0.7 Hz swing: smooth, but its level wanders far more than the
  // coast's scatter: floating too.
  const SampleStore slow = record([](double t) { return t < 2 ? 1.5 + 0.4 * std::sin(2 * M_PI * 49.3 * t) : 2.7 - 0.1 * (t - 2); },
                                  4.0, 0.004, 0.0, 24);
  EXPECT_EQ(name_lead_in(slow, 2.0, 2.7, -0.1, 0.004, &sp), "floating");
  EXPECT_GT(sp.pre_sd, 0.1);
}

TEST(LeadIn, ALeadInFallingIntoTheCoastAtItsPaceIsMoreCoast) {
  // The cut was earlier than the split: the "lead-in" already falls at the coast's rate, into it.
  const SampleStore s = record([](double t) { return 3.0 - 0.1 * t; }, 4.0, 0.003, 0.0, 25);
  CutSplit sp;
  name_lead_in(s, 2.0, 2.8, -0.1, 0.003, &sp);
  EXPECT_TRUE(sp.pre_declining);
  EXPECT_FALSE(sp.pre_flat);
}

TEST(LeadIn, TooFewSamplesBeforeTheCutIsNone) {
  const SampleStore s = record([](double t) { return 2.7 - 0.1 * t; }, 2.0, 0.004);
  CutSplit sp;
  sp.a = 0;
  sp.cut_index = sp.pre_end = 2;
  describe_lead_in(s, sp);
  EXPECT_EQ(classify_lead_in(sp), "none");
}
