// column_names.hpp: the units a header gives, in the spellings labs and loggers write.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "spindown/column_names.hpp"

using namespace spindown;

namespace {

struct Expect {
  const char* header;
  const char* base;
  const char* unit;
};

}  // namespace

TEST(ColumnNames, UnitsInEverySpelling) {
  const Expect cases[] = {
      {"Drehzahl [U/min]", "drehzahl", "u/min"}, {"n [1/min]", "n", "1/min"},
      {"omega (rad/s)", "omega", "rad/s"},        {"Voltage [mV]", "voltage", "mv"},
      {"time (s)", "time", "s"},                  {"t[ms]", "t", "ms"},
      {"time_ms", "time", "ms"},                  {"speed_rpm", "speed", "rpm"},
      {"omega_rad_s", "omega", "rad_s"},          {"Speed RPM", "speed", "rpm"},
      {"t / s", "t", "s"},                        {"n / (1/min)", "n", "1/min"},
      {"Zeit in ms", "zeit", "ms"},               {"Time, s", "time", "s"},
      {"Motor speed, rpm", "motor speed", "rpm"}, {"t [\xC2\xB5s]", "t", "us"},
      {"n [min\xE2\x81\xBB\xC2\xB9]", "n", "min^-1"}, {"millis", "millis", ""},
      {"rpm", "rpm", ""},                         {"Speed (left wheel)", "speed (left wheel)", ""},
      {"RR_Wheel,Speed", "rr_wheel,speed", ""},
  };
  for (const auto& c : cases) {
    const ColumnName n = describe_column(c.header);
    EXPECT_EQ(n.base, c.base) << c.header;
    EXPECT_EQ(n.unit, c.unit) << c.header;
    EXPECT_EQ(n.name, c.header);
  }
}

TEST(ColumnNames, ValueUnitsAndTheirFactors) {
  auto unit = [](const char* header) { return implied_value_unit(describe_column(header)); };
  for (const char* rpm : {"Drehzahl [U/min]", "n [1/min]", "speed_rpm", "rpm", "Speed (RPM)", "n [min^-1]",
                          "n [min\xE2\x81\xBB\xC2\xB9]"}) {
    ASSERT_TRUE(unit(rpm)) << rpm;
    EXPECT_EQ(unit(rpm)->quantity, Quantity::rpm) << rpm;
    EXPECT_EQ(unit(rpm)->scale, 1) << rpm;
  }
  EXPECT_EQ(unit("omega (rad/s)")->quantity, Quantity::rad_per_s);
  EXPECT_EQ(unit("omega")->quantity, Quantity::rad_per_s);
  EXPECT_EQ(unit("volts")->quantity, Quantity::back_emf_volts);
  const auto mv = unit("Voltage [mV]");
  ASSERT_TRUE(mv);
  EXPECT_EQ(mv->quantity, Quantity::back_emf_volts);
  EXPECT_DOUBLE_EQ(mv->scale, 1e-3);
  // 1/s: rad/s for an angular velocity, revolutions per second for a speed n.
  EXPECT_EQ(unit("omega [1/s]")->quantity, Quantity::rad_per_s);
  EXPECT_EQ(unit("n [1/s]")->quantity, Quantity::rpm);
  EXPECT_DOUBLE_EQ(unit("n [1/s]")->scale, 60);
  EXPECT_DOUBLE_EQ(unit("f [Hz]")->scale, 60);
  EXPECT_NEAR(unit("w [\xC2\xB0/s]")->scale, std::numbers::pi / 180, 1e-15);
  EXPECT_FALSE(unit("speed"));
  EXPECT_FALSE(unit("speed [km/h]"));
}

TEST(ColumnNames, TimeAndValueNames) {
  EXPECT_TRUE(is_time_name(describe_column("Zeit (s)")));
  EXPECT_TRUE(is_time_name(describe_column("millis")));
  EXPECT_TRUE(is_time_name(describe_column("Time, s")));
  EXPECT_EQ(implied_time_unit(describe_column("millis")), TimeUnit::ms);
  EXPECT_EQ(implied_time_unit(describe_column("Zeit (s)")), TimeUnit::s);
  EXPECT_EQ(implied_time_unit(describe_column("time")), std::nullopt);
  EXPECT_TRUE(is_value_name(describe_column("Drehzahl (U/min)")));
  EXPECT_TRUE(is_value_name(describe_column("Motor speed, rpm")));
  EXPECT_FALSE(is_value_name(describe_column("Supply current, A")));
  EXPECT_FALSE(is_value_name(describe_column("Winding temp, \xC2\xB0" "C")));
}

TEST(ColumnNames, AnUnknownUnitIsSaidWithTheLikelyOption) {
  const ColumnName kmh = describe_column("Speed [km/h]");
  EXPECT_TRUE(unknown_value_unit(kmh));
  EXPECT_EQ(likely_value_unit(kmh), "rpm");
  EXPECT_FALSE(unknown_value_unit(describe_column("Drehzahl [U/min]")));
  EXPECT_EQ(likely_value_unit(describe_column("Spannung")), "V");
  EXPECT_EQ(likely_value_unit(describe_column("omega")), "rad/s");
  EXPECT_EQ(likely_value_unit(describe_column("Kanal 3")), "");
}

TEST(ColumnNames, ParseUnitsForTheCommandLine) {
  EXPECT_EQ(parse_time_unit("ms"), TimeUnit::ms);
  EXPECT_EQ(parse_time_unit("Seconds"), TimeUnit::s);
  EXPECT_EQ(parse_time_unit("\xC2\xB5s"), TimeUnit::us);
  EXPECT_EQ(parse_time_unit("\xCE\xBCs"), TimeUnit::us);
  EXPECT_EQ(parse_time_unit("micros"), TimeUnit::us);
  EXPECT_FALSE(parse_time_unit("min"));
  EXPECT_EQ(time_unit_name(TimeUnit::us), "us");
  EXPECT_DOUBLE_EQ(time_units_per_second(TimeUnit::ms), 1000);
  EXPECT_EQ(parse_value_unit("U/min")->quantity, Quantity::rpm);
  EXPECT_EQ(parse_value_unit("mV")->name, "mV");
  EXPECT_FALSE(parse_value_unit("A"));
}
