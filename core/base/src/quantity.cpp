#include "spindown/quantity.hpp"

#include <algorithm>
#include <cctype>
#include <numbers>
#include <string>

namespace spindown {

std::string_view quantity_unit(Quantity q) {
  switch (q) {
    case Quantity::back_emf_volts: return "V";
    case Quantity::rpm: return "rpm";
    case Quantity::rad_per_s: return "rad/s";
  }
  return "?";
}

std::optional<Quantity> parse_quantity(std::string_view unit) {
  std::string u(unit);
  std::transform(u.begin(), u.end(), u.begin(), [](unsigned char c) { return std::tolower(c); });
  if (u == "v" || u == "volt" || u == "volts") return Quantity::back_emf_volts;
  if (u == "rpm" || u == "1/min") return Quantity::rpm;
  if (u == "rad/s" || u == "rad_s" || u == "rads" || u == "rad/sec") return Quantity::rad_per_s;
  return std::nullopt;
}

double value_per_rad_per_s(Quantity q, double kb_v_s_per_rad) {
  switch (q) {
    case Quantity::back_emf_volts: return kb_v_s_per_rad;
    case Quantity::rpm: return 60.0 / (2.0 * std::numbers::pi);
    case Quantity::rad_per_s: return 1.0;
  }
  return 1.0;
}

}  // namespace spindown
