// Run finding scored against the physics that made each recording (tests/detection_truth.hpp):
// per pattern, the runs missed and invented, the cut and end errors in sample periods, stops
// claimed where the motor never stopped, and partial coasts given a lead-in. Each pattern has
// limits it must keep; the table is printed so a change's effect on every pattern shows.
#include <gtest/gtest.h>

#include <cstdio>

#include "detection_truth.hpp"

namespace spindown::truth {
namespace {

// The most each pattern may miss by, in sample periods (90th percentile over its recordings).
// Before the truth corpus (2026-11-25, 12 recordings each): ramp cut 318, hand spin 16,
// per-revolution sensor 22 (cut) and 100 (end), long coast 2139 (end, cut at 600 s), 7 of 12
// slow viscous coasts stopped while still falling, 12 of 12 resets gave an invented run, 11 of
// 12 recordings starting mid-coast a lead-in, no dropout left out. The slow logger (issue 32: the
// heavy flywheel logged once a second) was added when the windows began to follow the sample rate:
// before, all 12 were missed (a 4-s window held 5 readings). Its stops are still rough (end p90
// 67.5 periods, 2026-11-28): on the 2-decimal print a few come early (the long hold window, 3 % of
// the coast, holds 15 readings, too few to see the end's slope) or are not found before the
// recording ends; its limit records that, to be tightened.
struct Limits {
  const char* pattern;
  double cut_p90, end_p90;
};
constexpr Limits limits[] = {
    {"lab", 1.0, 6.0},          {"ramp", 8.0, 6.0},
    {"hand spin", 3.0, 6.0},    {"pause before the coast", 1.0, 6.0},
    {"long coast", 1.0, 80.0},  {"dropouts", 1.0, 6.0},
    {"per-rev sensor", 3.0, 40.0}, {"reset mid-coast", 1.0, 1.0},
    {"slow viscous", 1.0, 1.0}, {"starts mid-coast", 1.0, 6.0},
    {"uneven sampling", 1.0, 6.0}, {"three runs", 1.0, 6.0},
    {"nudge after a run", 1.0, 6.0},  {"nudge before a run", 1.0, 6.0},
    {"floating pin", 1.0, 6.0},   {"slow logger", 1.0, 70.0},
};

TEST(DetectionTruth, ScoresEachPattern) {
  const auto scores = score_all(make_cases(12));
  std::printf("%s", score_table(scores).c_str());
  ASSERT_EQ(scores.size(), std::size(limits));
  for (const Limits& l : limits) {
    SCOPED_TRACE(l.pattern);
    ASSERT_TRUE(scores.count(l.pattern));
    const PatternScore& s = scores.at(l.pattern);
    EXPECT_EQ(s.truth_runs, 12 * (std::string(l.pattern) == "three runs" ? 3 : 1));
    EXPECT_EQ(s.missed, 0);
    EXPECT_EQ(s.invented, s.invented_said);  // none, or each one called a fragment in a warning
    EXPECT_LE(PatternScore::quantile(s.cut_err, 0.9), l.cut_p90);
    EXPECT_LE(PatternScore::quantile(s.end_err, 0.9), l.end_p90);
    EXPECT_EQ(s.false_stops, 0);
    EXPECT_EQ(s.partial_wrong, 0);
    EXPECT_EQ(s.false_lost, 0);
    EXPECT_LE(s.missed_lost, s.truth_runs / 10);
    EXPECT_GE(s.rejected, s.bad_samples * 9 / 10);
    // Contact bounce is left out less surely: where the open pin read what the motor reads, a
    // bounce sample between the two is no further off the coast than the hum was.
    EXPECT_GE(s.bounces_out, s.bounces * 7 / 10);
    EXPECT_EQ(s.wrongly_rejected, 0);
  }
}

// The live fitter's cap (max_coast_s) closes a long coast with a warning, and the rest of that
// coast is no second run.
TEST(DetectionTruth, ACappedCoastIsOneRun) {
  for (const Case& c : make_cases(3)) {
    if (c.pattern != "long coast") continue;
    RunOptions opt;
    opt.max_coast_s = 300;  // these coasts last 9-12 minutes
    const Segmentation seg = find_runs(c.rec, opt);
    ASSERT_EQ(seg.runs.size(), 1u);
    EXPECT_EQ(seg.runs[0].end, Run::End::cap);
    bool warned = false;
    for (const Diagnostic& d : seg.diagnostics)
      warned = warned || (d.severity == Diagnostic::Severity::warning && d.message.find("the longest coast kept") != std::string::npos);
    EXPECT_TRUE(warned);
  }
}

}  // namespace
}  // namespace spindown::truth
