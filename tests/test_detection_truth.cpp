// Run finding scored against the physics that made each recording (tests/detection_truth.hpp):
// per pattern, the runs missed and invented, the cut and end errors in sample periods, stops
// claimed where the motor never stopped, and partial coasts given a lead-in. Each pattern has
// limits it must keep; the table is printed so a change's effect on every pattern shows.
#include <gtest/gtest.h>

#include <cstdio>

#include "detection_truth.hpp"

namespace spindown::truth {
namespace {

TEST(DetectionTruth, ScoresEachPattern) {
  const auto scores = score_all(make_cases(12));
  std::printf("%s", score_table(scores).c_str());
}

}  // namespace
}  // namespace spindown::truth
