#include <gtest/gtest.h>

#include <cmath>

#include "spindown/bench.hpp"
#include "spindown/lab_units.hpp"

using namespace spindown;

// The lab report's numbers (design §1), reproduced from its curve constants to the digits
// printed there: SI coefficient from the curve constant and the bench, then lab units.
namespace {
const BenchParams lab = BenchParams::lab_default();
const double J = lab.inertia_kg_m2;
const double Kb = lab.kb_v_s_per_rad;

// |x − printed| within half a unit of the last printed digit.
void expect_printed(double x, double printed, int decimals) {
  EXPECT_LE(std::fabs(x - printed), 0.5 * std::pow(10.0, -decimals) + 1e-12) << x << " vs printed " << printed;
}
}  // namespace

TEST(LabUnits, InertiaOfTheLabBench) {
  expect_printed(inertia_to_g_cm2(J), 112.687602, 6);
  // Flywheel r = 2 cm, h = 1.5 cm, aluminium, plus the datasheet rotor's 10.9 g·cm².
  expect_printed(inertia_to_g_cm2(cylinder_inertia(0.02, 0.015, 2700) + 10.9e-7), 112.687602, 5);
}

TEST(LabUnits, ViscousC1FromExponentialRate) {
  const double B[] = {0.124, 0.096, 0.111, 0.088};
  const double c1[] = {13.973, 10.818, 12.508, 9.917};
  for (int i = 0; i < 4; ++i) expect_printed(viscous_to_g_cm2_per_s(B[i] * J), c1[i], 3);
}

TEST(LabUnits, CoulombC2FromLinearSlope) {
  const double A[] = {-0.0993, -0.0946, -0.1007, -0.1541};
  const double c2[] = {1382.726, 1317.279, 1402.220, 2145.801};
  for (int i = 0; i < 4; ++i) expect_printed(torque_to_g_cm2_rad_per_s2(-A[i] * J / Kb), c2[i], 3);
}

TEST(LabUnits, CombinedC3C4FromOffsetExponential) {
  const double A[] = {-5.0581, -2.8813, -5.13509, -5.7502};
  const double C[] = {-0.01617, -0.02505, -0.01597, -0.01484};
  const double c3[] = {1.822, 2.823, 1.800, 1.672};
  const double c4[] = {1138.89633, 1005.039132, 1141.930672, 1188.238483};
  const int c4_decimals[] = {5, 6, 6, 6};
  for (int i = 0; i < 4; ++i) {
    expect_printed(viscous_to_g_cm2_per_s(-C[i] * J), c3[i], 3);
    expect_printed(torque_to_g_cm2_rad_per_s2(A[i] * C[i] * J / Kb), c4[i], c4_decimals[i]);
  }
}

TEST(LabUnits, UnitLookupByParameterUnit) {
  auto viscous = lab_unit_for("N*m*s/rad");
  ASSERT_TRUE(viscous);
  EXPECT_EQ(viscous->per_si, 1e7);
  EXPECT_EQ(viscous->ascii, "g*cm^2/s");
  EXPECT_EQ(viscous->pretty, "g·cm²·s⁻¹");
  auto torque = lab_unit_for("N*m");
  ASSERT_TRUE(torque);
  EXPECT_EQ(torque->pretty, "g·cm²·rad·s⁻²");
  EXPECT_EQ(torque->per_si, 1e7);
  auto inertia = lab_unit_for("kg*m^2");
  ASSERT_TRUE(inertia);
  EXPECT_EQ(inertia->pretty, "g·cm²");
  // Units the lab kept as they are have no lab spelling.
  EXPECT_FALSE(lab_unit_for("rad/s"));
  EXPECT_FALSE(lab_unit_for("V"));
  EXPECT_FALSE(lab_unit_for("1/s"));
}

TEST(LabUnits, PrettyUnits) {
  EXPECT_EQ(pretty_unit("N*m*s/rad"), "N·m·s/rad");
  EXPECT_EQ(pretty_unit("N*m"), "N·m");
  EXPECT_EQ(pretty_unit("1/s"), "s⁻¹");
  EXPECT_EQ(pretty_unit("furlong"), "furlong");  // unknown units pass through unchanged
}
