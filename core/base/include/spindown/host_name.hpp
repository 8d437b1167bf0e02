#pragma once
#include <string>

namespace spindown {

// This host's name as gethostname(2) gives it; "unknown" when that fails or is empty. What
// status_t.host and config_t.host carry, and what the doctor compares them with.
std::string host_name();

}  // namespace spindown
