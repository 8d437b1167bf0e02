#pragma once
// A health verdict in words for the terminal and the reports.
#include <string>
#include <string_view>

#include "spindown/motor_health.hpp"

namespace spindown {

// "health: SERVICE — reason" and one line per finding with its numbers and uncertainty.
std::string format_health_verdict(const HealthVerdict& verdict, std::string_view indent = "  ");

}  // namespace spindown
