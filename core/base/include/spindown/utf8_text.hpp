#pragma once
// UTF-8 in messages: text that came from outside (a file's bytes, a host name in a received LCM
// message) shown so that what is printed stays valid UTF-8, which JSON and terminals need.
#include <cstddef>
#include <string>
#include <string_view>

namespace spindown::text {

// Length of the valid UTF-8 sequence starting at s[i] (1 to 4); 0 when none starts there.
std::size_t utf8_sequence_length(std::string_view s, std::size_t i);
// s unquoted and uncut, every byte that is not part of valid UTF-8 written as \xNN.
std::string escape_invalid_utf8(std::string_view s);

}  // namespace spindown::text
