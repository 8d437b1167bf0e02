#pragma once
// LCM channel names of the suite: SPINDOWN.<bench>.SAMPLE|CONFIG|RUN|FIT|EXPLAIN|STATUS, and the
// bench id rule [A-Za-z0-9_-]{1,32} (design §3). Every service builds its names here.
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

enum class ChannelKind { sample, config, run, fit, explain, status };

inline constexpr std::string_view channel_prefix = "SPINDOWN.";
inline constexpr std::size_t max_bench_id_length = 32;

// True when id matches [A-Za-z0-9_-]{1,32}; otherwise false and, when why is given, the reason.
bool is_valid_bench_id(std::string_view id, std::string* why = nullptr);

// "SAMPLE", "CONFIG", …
std::string_view channel_suffix(ChannelKind kind);

// "SPINDOWN.<bench>.<SUFFIX>"; throws std::invalid_argument naming the bad bench id.
std::string channel_name(std::string_view bench, ChannelKind kind);

struct ParsedChannel {
  std::string bench;
  ChannelKind kind;
};
// The bench and suffix of "SPINDOWN.<bench>.<SUFFIX>" as views into the channel, neither checked
// (a reader that counts a bad bench id apart needs them); nullopt without the prefix or a dot.
struct ChannelParts {
  std::string_view bench, suffix;
};
std::optional<ChannelParts> split_channel(std::string_view channel);
// The kind a channel's suffix names; nullopt for a suffix that is not the suite's.
std::optional<ChannelKind> channel_kind(std::string_view suffix);
// The inverse of channel_name; nullopt for channels that are not the suite's.
std::optional<ParsedChannel> parse_channel(std::string_view channel);

}  // namespace spindown
