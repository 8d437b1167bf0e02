#pragma once
// A text in lower case, ASCII letters only (UTF-8's other bytes as they are): for matching names
// and units in files ("Drehzahl [U/min]" -> "drehzahl [u/min]") without a locale.
#include <string>
#include <string_view>

namespace spindown {

inline std::string ascii_lower(std::string_view s) {
  std::string out(s);
  for (char& c : out)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return out;
}

}  // namespace spindown
