#include "spindown/lcm_url.hpp"
#include "spindown/trim.hpp"

#include <charconv>
#include <cstdlib>
#include <fmt/format.h>

namespace spindown {

namespace {
bool to_long(std::string_view s, long& out) {
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

}  // namespace

std::optional<LcmUrl> parse_lcm_url(std::string_view url, std::string* why) {
  auto fail = [&](std::string reason) -> std::optional<LcmUrl> {
    if (why) *why = fmt::format("LCM URL '{}': {}", url, reason);
    return std::nullopt;
  };
  LcmUrl u;
  u.text = std::string(url);
  const auto sep = url.find("://");
  if (sep == std::string_view::npos || sep == 0) return fail("not PROVIDER://… (e.g. udpm://239.255.76.67:7667?ttl=1)");
  u.provider = std::string(url.substr(0, sep));
  std::string_view rest = url.substr(sep + 3);
  std::string_view query;
  if (const auto q = rest.find('?'); q != std::string_view::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }
  while (!query.empty()) {
    const auto amp = query.find('&');
    const std::string_view item = query.substr(0, amp);
    const auto eq = item.find('=');
    if (!item.empty()) {
      if (eq == std::string_view::npos) return fail(fmt::format("option '{}' has no '=value'", item));
      u.options[std::string(item.substr(0, eq))] = std::string(item.substr(eq + 1));
    }
    if (amp == std::string_view::npos) break;
    query = query.substr(amp + 1);
  }
  if (u.provider != "udpm") {
    u.address = std::string(rest);
    return u;
  }
  // udpm with nothing after :// is LCM's default group and port.
  if (rest.empty()) rest = "239.255.76.67:7667";
  const auto colon = rest.rfind(':');
  if (colon == std::string_view::npos) return fail("udpm needs GROUP:PORT");
  u.address = std::string(rest.substr(0, colon));
  long port = 0;
  if (!to_long(rest.substr(colon + 1), port) || port < 1 || port > 65535)
    return fail(fmt::format("port '{}' is not 1…65535", rest.substr(colon + 1)));
  u.port = static_cast<int>(port);
  if (const auto it = u.options.find("ttl"); it != u.options.end()) {
    long ttl = 0;
    if (!to_long(it->second, ttl) || ttl < 0 || ttl > 255) return fail(fmt::format("ttl '{}' is not 0…255", it->second));
    u.ttl = static_cast<int>(ttl);
    u.ttl_given = true;
  }
  if (const auto it = u.options.find("recv_buf_size"); it != u.options.end()) {
    long bytes = 0;
    if (!to_long(it->second, bytes) || bytes < 0) return fail(fmt::format("recv_buf_size '{}' is not a size", it->second));
    u.recv_buf_size = bytes;
  }
  return u;
}

std::map<std::string, std::string> parse_env_file(std::string_view text) {
  std::map<std::string, std::string> out;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    std::string_view line = trim(text.substr(0, nl));
    text = nl == std::string_view::npos ? std::string_view() : text.substr(nl + 1);
    if (line.empty() || line.front() == '#' || line.front() == ';') continue;
    if (line.rfind("export ", 0) == 0) line = trim(line.substr(7));
    const auto eq = line.find('=');
    if (eq == std::string_view::npos || eq == 0) continue;
    const std::string key(trim(line.substr(0, eq)));
    std::string_view value = trim(line.substr(eq + 1));
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'') && value.back() == value.front())
      value = value.substr(1, value.size() - 2);
    out[key] = std::string(value);
  }
  return out;
}

ResolvedLcmUrl resolve_lcm_url(const std::string& cli, const std::optional<std::string>& env,
                               const std::optional<std::string>& env_file, std::string_view env_file_path) {
  if (!cli.empty()) return {cli, "--lcm-url"};
  if (env && !env->empty()) return {*env, "LCM_DEFAULT_URL"};
  if (env_file && !env_file->empty()) return {*env_file, std::string(env_file_path)};
  return {std::string(lcm_builtin_default_url), "LCM's default"};
}

std::string with_receive_buffer(std::string url, long bytes) {
  const char* env = std::getenv("LCM_DEFAULT_URL");
  url = resolve_lcm_url(url, env ? std::optional<std::string>(env) : std::nullopt, std::nullopt).url;
  if (bytes <= 0 || url.rfind("udpm://", 0) != 0 || url.find("recv_buf_size") != std::string::npos) return url;
  return url + (url.find('?') == std::string::npos ? "?" : "&") + fmt::format("recv_buf_size={}", bytes);
}

std::string lcm_destination(const std::string& url) {
  std::string effective = url;
  if (effective.empty()) {
    const char* env = std::getenv("LCM_DEFAULT_URL");
    effective = env && *env ? std::string(env) : std::string(lcm_builtin_default_url);
  }
  const auto parsed = parse_lcm_url(effective);
  if (!parsed || parsed->provider != "udpm") return {};
  return parsed->address + ":" + std::to_string(parsed->port);
}

}  // namespace spindown
