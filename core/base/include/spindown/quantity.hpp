#pragma once
// What a sample's value measures, and the conversion to shaft speed.
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

enum class Quantity { back_emf_volts, rpm, rad_per_s };

// Stable names used in files, messages and JSON: "V", "rpm", "rad/s".
std::string_view quantity_unit(Quantity q);
std::optional<Quantity> parse_quantity(std::string_view unit);  // accepts V, v, volt(s), rpm, rad/s

// Multiply ω (rad/s) by this to get the quantity's value; K_b in V·s/rad.
double value_per_rad_per_s(Quantity q, double kb_v_s_per_rad);

}  // namespace spindown
