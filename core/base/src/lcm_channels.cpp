#include "spindown/lcm_channels.hpp"

#include <array>
#include <fmt/format.h>
#include <stdexcept>

namespace spindown {

namespace {
constexpr std::array<std::pair<ChannelKind, std::string_view>, 6> kSuffixes{{
    {ChannelKind::sample, "SAMPLE"},
    {ChannelKind::config, "CONFIG"},
    {ChannelKind::run, "RUN"},
    {ChannelKind::fit, "FIT"},
    {ChannelKind::explain, "EXPLAIN"},
    {ChannelKind::status, "STATUS"},
}};

bool is_id_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
         c == '-';
}
}  // namespace

bool is_valid_bench_id(std::string_view id, std::string* why) {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (id.empty()) return fail("bench id is empty (want 1-32 of A-Z a-z 0-9 _ -)");
  if (id.size() > max_bench_id_length)
    return fail(fmt::format("bench id is {} characters long (at most {})", id.size(), max_bench_id_length));
  for (std::size_t i = 0; i < id.size(); ++i) {
    if (!is_id_char(id[i])) {
      const auto c = static_cast<unsigned char>(id[i]);
      return fail(fmt::format("bench id has character 0x{:02x} at position {} (allowed: A-Z a-z 0-9 _ -)",
                              c, i + 1));
    }
  }
  return true;
}

std::string_view channel_suffix(ChannelKind kind) {
  for (const auto& [k, s] : kSuffixes)
    if (k == kind) return s;
  return "UNKNOWN";
}

std::string channel_name(std::string_view bench, ChannelKind kind) {
  std::string why;
  if (!is_valid_bench_id(bench, &why)) throw std::invalid_argument(why);
  return fmt::format("{}{}.{}", channel_prefix, bench, channel_suffix(kind));
}

std::optional<ChannelParts> split_channel(std::string_view channel) {
  if (!channel.starts_with(channel_prefix)) return std::nullopt;
  channel.remove_prefix(channel_prefix.size());
  const auto dot = channel.rfind('.');
  if (dot == std::string_view::npos) return std::nullopt;
  return ChannelParts{channel.substr(0, dot), channel.substr(dot + 1)};
}

std::optional<ChannelKind> channel_kind(std::string_view suffix) {
  for (const auto& [k, s] : kSuffixes)
    if (s == suffix) return k;
  return std::nullopt;
}

std::optional<ParsedChannel> parse_channel(std::string_view channel) {
  const auto parts = split_channel(channel);
  if (!parts || !is_valid_bench_id(parts->bench)) return std::nullopt;
  const auto kind = channel_kind(parts->suffix);
  if (!kind) return std::nullopt;
  return ParsedChannel{std::string(parts->bench), *kind};
}

}  // namespace spindown
