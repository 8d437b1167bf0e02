// The effect library: every effect describes itself, its derivatives are right, and base
// models parse.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "spindown/effects.hpp"

using namespace spindown;

TEST(Effects, LibraryHoldsTheFiveEffectsWithTheirDescriptions) {
  for (const char* name : {"viscous", "coulomb", "stribeck", "windage", "sensor_offset"}) {
    const Effect* e = find_effect(name);
    ASSERT_NE(e, nullptr) << name;
    EXPECT_FALSE(e->meaning.empty()) << name;
    EXPECT_FALSE(e->term.empty()) << name;
    EXPECT_FALSE(e->signature.empty()) << name;
    ASSERT_GE(e->size(), 1) << name;
    const RunScale scale;
    for (const auto& p : e->params) {
      EXPECT_FALSE(p.unit.empty()) << name << " " << p.name;
      EXPECT_LT(p.lower(scale), p.upper(scale)) << name << " " << p.name;
      EXPECT_GT(p.typical(scale), p.lower(scale)) << name << " " << p.name;
      EXPECT_LT(p.typical(scale), p.upper(scale)) << name << " " << p.name;
    }
    if (e->kind == EffectKind::torque)
      EXPECT_NE(e->rate, nullptr) << name;
    else
      EXPECT_NE(e->reading, nullptr) << name;
  }
  EXPECT_EQ(find_effect("magic"), nullptr);
  EXPECT_EQ(effect_names().size(), effect_library().size());
}

TEST(Effects, TorqueTermsMatchTheirFormulas) {
  const double w = 50;
  {
    const double p[] = {0.02};
    EXPECT_DOUBLE_EQ(find_effect("viscous")->rate(p, w, nullptr, nullptr), 0.02 * w);
  }
  {
    const double p[] = {9.0};
    EXPECT_DOUBLE_EQ(find_effect("coulomb")->rate(p, w, nullptr, nullptr), 9.0);
  }
  {
    const double p[] = {8.0, 35.0};
    EXPECT_NEAR(find_effect("stribeck")->rate(p, w, nullptr, nullptr), 8.0 * std::exp(-std::pow(w / 35.0, 2)), 1e-12);
  }
  {
    const double p[] = {6e-5};
    EXPECT_DOUBLE_EQ(find_effect("windage")->rate(p, w, nullptr, nullptr), 6e-5 * w * w);
  }
  {
    const double p[] = {0.06};
    EXPECT_DOUBLE_EQ(find_effect("sensor_offset")->reading(p, w, nullptr), 0.06);
  }
}

// Analytic derivatives against central differences, for every torque effect.
TEST(Effects, DerivativesMatchFiniteDifferences) {
  const double params[][2] = {{0.02, 0}, {9.0, 0}, {8.0, 35.0}, {6e-5, 0}};
  const char* names[] = {"viscous", "coulomb", "stribeck", "windage"};
  for (int k = 0; k < 4; ++k) {
    const Effect* e = find_effect(names[k]);
    for (double w : {0.0, 5.0, 30.0, 120.0, 300.0}) {
      double p[2] = {params[k][0], params[k][1]};
      double dw = 0, dp[2] = {0, 0};
      e->rate(p, w, &dw, dp);
      const double h = 1e-4 * std::max(1.0, w);
      const double num_w = (e->rate(p, w + h, nullptr, nullptr) - e->rate(p, std::max(w - h, 0.0), nullptr, nullptr)) /
                           (w + h - std::max(w - h, 0.0));
      EXPECT_NEAR(dw, num_w, 1e-6 * (std::abs(num_w) + 1)) << names[k] << " w=" << w;
      for (int j = 0; j < e->size(); ++j) {
        const double hp = 1e-6 * std::max(std::abs(p[j]), 1e-9);
        double up[2] = {p[0], p[1]}, dn[2] = {p[0], p[1]};
        up[j] += hp;
        dn[j] -= hp;
        const double num = (e->rate(up, w, nullptr, nullptr) - e->rate(dn, w, nullptr, nullptr)) / (2 * hp);
        EXPECT_NEAR(dp[j], num, 1e-5 * (std::abs(num) + 1e-9)) << names[k] << " p" << j << " w=" << w;
      }
    }
  }
}

TEST(Effects, ParsesBaseModels) {
  std::string why;
  auto combined = parse_effect_list("combined", &why);
  ASSERT_EQ(combined.size(), 2u);
  EXPECT_EQ(combined[0]->name, "viscous");
  EXPECT_EQ(combined[1]->name, "coulomb");
  auto list = parse_effect_list("windage, coulomb,coulomb", &why);
  ASSERT_EQ(list.size(), 2u);  // library order, no duplicates
  EXPECT_EQ(list[0]->name, "coulomb");
  EXPECT_EQ(list[1]->name, "windage");
  EXPECT_TRUE(parse_effect_list("viscous,friction", &why).empty());
  EXPECT_NE(why.find("unknown effect 'friction'"), std::string::npos) << why;
  EXPECT_TRUE(parse_effect_list(" , ", &why).empty());
}
