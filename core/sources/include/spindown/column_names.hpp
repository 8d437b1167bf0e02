#pragma once
// What a delimited text's header says about its columns: which is the time and which the speed
// or back-EMF, and in which units, as people write them in any language a lab meets:
//   in brackets   "time (s)", "Drehzahl [U/min]", "n [1/min]", "omega (rad/s)", "Voltage [mV]"
//   after a slash "t/s", "U / V", "n / min^-1"
//   after "in"    "Zeit in ms", "Drehzahl in U/min"
//   as a suffix   "time_ms", "speed_rpm", "omega_rad_s", "Speed RPM"
//   as the name   "millis", "rpm", "volts"
// or in a row of units under the names ("time;speed" then "s;rpm"). Units are matched without
// case and blanks, µ/μ as u and ⁻¹ as ^-1. A value unit may carry a factor: mV (×0.001),
// revolutions per second (rps, Hz, U/s: ×60 rpm), degrees per second (×π/180 rad/s).
#include <optional>
#include <string>
#include <string_view>

#include "spindown/quantity.hpp"

namespace spindown {

enum class TimeUnit { s, ms, us };
std::string_view time_unit_name(TimeUnit unit);                // "s", "ms", "us"
std::optional<TimeUnit> parse_time_unit(std::string_view unit);  // s, sec, Sek, ms, millis, us, µs, micros…
double time_units_per_second(TimeUnit unit);

// A value column's unit: its quantity, and the factor that turns a reading into it (mV: 0.001 V).
struct ValueUnit {
  Quantity quantity = Quantity::back_emf_volts;
  double scale = 1;
  std::string name;  // as spindown names it: "V", "mV", "rpm", "rev/s", "rad/s", "deg/s"
};
// column_base: the column's name without its unit ("omega", "n"), which decides what "1/s" is
// (rad/s for an angular velocity ω, revolutions per second otherwise); "" when not known.
std::optional<ValueUnit> parse_value_unit(std::string_view unit, std::string_view column_base = {});
// The units parse_value_unit reads, for messages.
std::string_view value_units_read();

// One header field.
struct ColumnName {
  std::string name;  // as written (bytes that are not UTF-8 as \xNN)
  std::string base;  // lower case, without its unit: "Drehzahl [U/min]" -> "drehzahl"
  std::string unit;  // the unit as written, lower case without blanks ("u/min"); "" when none
};
ColumnName describe_column(std::string_view header_field);
// A unit from a row of units under the names (" [rpm] ", "(s)", "U/min"); "" when the field is
// not one.
std::string unit_cell(std::string_view field);

bool is_time_name(const ColumnName& c);   // "time", "t", "zeit", "millis", "timestamp", …
bool is_value_name(const ColumnName& c);  // "volts", "rpm", "speed", "drehzahl", "omega", "n", …
// The time unit the column's name or unit says ("time_ms", "millis", "t [s]"); nullopt when none.
std::optional<TimeUnit> implied_time_unit(const ColumnName& c);
// The value unit the column's name or unit says ("rpm", "volts", "n [U/min]"); nullopt when none
// or when its unit is not one spindown reads (unknown_value_unit then says so).
std::optional<ValueUnit> implied_value_unit(const ColumnName& c);
// A unit written in the header that is neither a time nor a value unit spindown reads ("km/h").
bool unknown_value_unit(const ColumnName& c);
// The --value-unit a user most likely means for a column the header gives no usable unit for,
// from its name: "rpm" for a speed or Drehzahl, "rad/s" for ω, "V" for a voltage; "" when the
// name says nothing.
std::string_view likely_value_unit(const ColumnName& c);

}  // namespace spindown
