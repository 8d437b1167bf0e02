#pragma once
// The discrepancy workflow's result as the SPINDOWN.<bench>.EXPLAIN message (design §3, §6):
// the same story `spindown explain` tells, in explain_t's flat arrays.
#include <cstdint>
#include <string>

#include <spindown/explain_t.hpp>

#include "spindown/explain.hpp"

namespace spindown {

explain_t to_explain_message(const ExplainResult& result, const std::string& bench, std::int64_t utime);

}  // namespace spindown
