#include "spindown/quantity.hpp"

#include <numbers>
#include <string>

#include "spindown/ascii_lower.hpp"

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
  const std::string u = ascii_lower(unit);
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
