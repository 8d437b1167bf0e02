#pragma once
// The one way a `bool f(…, std::string* why)` refuses: *why (when given) says why, and the answer
// is false.
#include <string>
#include <utility>

namespace spindown {

inline bool fail_why(std::string* why, std::string text) {
  if (why) *why = std::move(text);
  return false;
}

}  // namespace spindown
