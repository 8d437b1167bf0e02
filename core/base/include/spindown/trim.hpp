#pragma once
// A text without its leading and trailing blanks (space, tab, CR, LF): a view into the same bytes.
#include <string_view>

namespace spindown {

inline std::string_view trim(std::string_view s) {
  constexpr std::string_view blanks = " \t\r\n";
  const auto b = s.find_first_not_of(blanks);
  if (b == std::string_view::npos) return {};
  return s.substr(b, s.find_last_not_of(blanks) - b + 1);
}

}  // namespace spindown
