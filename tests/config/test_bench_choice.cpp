// The one rule for J and K_b (choose_bench_params), one parameter at a time: the command line,
// else the bench's file, else the log's CONFIG, else the lab's defaults; each source named.
#include <gtest/gtest.h>

#include "spindown/bench_file.hpp"

namespace spindown {
namespace {

BenchFile file_with(bool j, bool kb) {
  BenchFile f;
  f.path = "benches/b1.toml";
  f.bench = "b1";
  f.params.inertia_kg_m2 = 2.0e-5;
  f.params.inertia_source = "flywheel geometry";
  f.params.kb_v_s_per_rad = 0.009;
  f.params.kb_source = "datasheet";
  f.sets_inertia = j;
  f.sets_kb = kb;
  return f;
}

BenchParams config_params() {
  BenchParams c;
  c.inertia_kg_m2 = 3.0e-5;
  c.inertia_source = "config";
  c.kb_v_s_per_rad = 0.007;
  c.kb_source = "config";
  return c;
}

TEST(BenchChoice, TheLabsDefaultsWhenNothingElseSaysSo) {
  const BenchParams p = choose_bench_params({}, nullptr, std::nullopt);
  EXPECT_DOUBLE_EQ(p.inertia_kg_m2, BenchParams{}.inertia_kg_m2);
  EXPECT_EQ(p.inertia_source, "lab default");
  EXPECT_EQ(p.kb_source, "lab default");
}

TEST(BenchChoice, ConfigOverTheDefaultsAndTheBenchFileOverTheConfig) {
  EXPECT_DOUBLE_EQ(choose_bench_params({}, nullptr, config_params()).inertia_kg_m2, 3.0e-5);
  const BenchFile f = file_with(true, false);
  const BenchParams p = choose_bench_params({}, &f, config_params());
  EXPECT_DOUBLE_EQ(p.inertia_kg_m2, 2.0e-5);  // the file sets J
  EXPECT_EQ(p.inertia_source, "flywheel geometry (benches/b1.toml)");
  EXPECT_DOUBLE_EQ(p.kb_v_s_per_rad, 0.007);  // the file sets no K_b: the CONFIG's
  EXPECT_EQ(p.kb_source, "config");
}

TEST(BenchChoice, TheCommandLineOverEverythingOneParameterAtATime) {
  BenchChoice cli;
  cli.given.inertia_kg_m2 = 4.0e-5;
  cli.given.inertia_source = "--inertia";
  cli.inertia_given = true;
  const BenchFile f = file_with(true, true);
  const BenchParams p = choose_bench_params(cli, &f, config_params());
  EXPECT_DOUBLE_EQ(p.inertia_kg_m2, 4.0e-5);
  EXPECT_EQ(p.inertia_source, "--inertia");
  EXPECT_DOUBLE_EQ(p.kb_v_s_per_rad, 0.009);  // K_b not given: the file's
  EXPECT_EQ(p.kb_source, "datasheet (benches/b1.toml)");
}

TEST(BenchChoice, TheUncertaintiesFollowTheSameRuleEachOnItsOwn) {
  BenchFile f = file_with(true, true);
  f.params.inertia_rel_error = 0.03;
  f.sets_inertia_error = true;  // the file gives J's uncertainty, not K_b's
  BenchParams config = config_params();
  config.inertia_rel_error = 0.01;
  config.kb_rel_error = 0.04;
  BenchChoice cli;
  BenchParams p = choose_bench_params(cli, &f, config);
  EXPECT_DOUBLE_EQ(p.inertia_rel_error, 0.03);  // the file's
  EXPECT_DOUBLE_EQ(p.kb_rel_error, 0.04);       // the CONFIG's
  cli.given.inertia_rel_error = 0.0;
  cli.inertia_error_given = true;  // --inertia-error 0: the user says J is exact
  p = choose_bench_params(cli, &f, config);
  EXPECT_DOUBLE_EQ(p.inertia_rel_error, 0.0);
  EXPECT_DOUBLE_EQ(choose_bench_params(BenchChoice{}, nullptr, std::nullopt).kb_rel_error, 0.0);  // none: exact
}

}  // namespace
}  // namespace spindown
