// The EXPLAIN message carries the workflow's story: base, each step with where the model and
// data disagreed, the final effects and their coefficients, the RMSE before and after.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "spindown/explain_message.hpp"
#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

using namespace spindown;

TEST(ExplainMessage, CarriesTheStepsOfACombinedRunExplainedFromViscous) {
  SyntheticRunSpec spec;  // the lab's bench: viscous + Coulomb friction
  spec.seed = 7;
  const SyntheticRun s = make_synthetic_run(spec);
  Recording rec;
  rec.source = "generated";
  for (std::size_t i = 0; i < s.t_ms.size(); ++i) rec.push(s.t_ms[i] / 1000.0, s.volts[i]);
  const Segmentation seg = find_runs(rec);
  ASSERT_EQ(seg.runs.size(), 1u);

  ExplainOptions opt;  // base: viscous, the lab's belief
  const ExplainResult r = explain_run(rec, seg.runs[0], opt);
  ASSERT_TRUE(r.ok) << r.message;
  const explain_t m = to_explain_message(r, "bench7", 123);

  EXPECT_EQ(m.utime, 123);
  EXPECT_EQ(m.bench, "bench7");
  EXPECT_EQ(m.run, seg.runs[0].number);
  ASSERT_EQ(m.nbase, 1);
  EXPECT_EQ(m.base[0], "viscous");
  ASSERT_GE(m.nsteps, 1);
  EXPECT_EQ(m.step_added[0], "coulomb");
  EXPECT_LT(m.step_rmse_after[0], m.step_rmse_before[0]);
  EXPECT_GE(m.nwhere, 1);
  EXPECT_EQ(static_cast<std::size_t>(m.nwhere), m.where_t_from_s.size());
  for (int i = 0; i < m.nwhere; ++i) EXPECT_LE(m.where_t_from_s[i], m.where_t_to_s[i]);
  EXPECT_NE(std::find(m.final_effects.begin(), m.final_effects.end(), "coulomb"), m.final_effects.end());
  EXPECT_EQ(static_cast<std::size_t>(m.nparams), m.param_name.size());
  EXPECT_EQ(m.param_value.size(), m.param_stderr.size());
  EXPECT_LT(m.rmse_final, m.rmse_base / 5);
  EXPECT_NE(m.story.find("coulomb"), std::string::npos);

  // The message survives LCM's encoding (every array length consistent with its count).
  std::vector<unsigned char> buf(m.getEncodedSize());
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  explain_t back{};
  ASSERT_EQ(back.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  EXPECT_EQ(back.step_added, m.step_added);
  EXPECT_EQ(back.story, m.story);
}
