#pragma once
// An LCM URL taken apart (provider://address:port?key=value&…), and where a program's URL comes
// from: --lcm-url, else the environment's LCM_DEFAULT_URL, else the services' env file
// (/etc/spindown/lcm.env), else LCM's own default.
#include <map>
#include <optional>
#include <string>
#include <string_view>

namespace spindown {

// LCM 1.3.1's URL when none is given: multicast that stays on this host.
inline constexpr std::string_view lcm_builtin_default_url = "udpm://239.255.76.67:7667?ttl=0";
inline constexpr std::string_view lcm_env_file_path = "/etc/spindown/lcm.env";

struct LcmUrl {
  std::string text;                          // as given
  std::string provider;                      // "udpm", "memq", "file", …
  std::string address;                       // udpm: the multicast group
  int port = 0;                              // udpm: the UDP port
  int ttl = 0;                               // udpm: 0 when not given (LCM's default)
  bool ttl_given = false;
  long recv_buf_size = 0;                    // 0 when not given
  std::map<std::string, std::string> options;
};

// The kernel receive buffer (SO_RCVBUF) the services ask LCM for, capped by net.core.rmem_max: it
// is what holds a burst while LCM's receive thread waits for a core. At 4 MB, 5 of 40 full-speed
// bursts of 50,000 messages lost datagrams at the logger's socket on a busy 2-core host (README,
// logger beside lcm-logger); at 16 MB none did.
inline constexpr long services_recv_buf_bytes = 16L << 20;

// url with recv_buf_size=bytes added, unless bytes <= 0, it is not udpm:// or it already says;
// "" means this process's LCM_DEFAULT_URL, else LCM's default.
std::string with_receive_buffer(std::string url, long bytes);

// Nullopt with the reason in why when the URL is not provider://…, or a udpm URL lacks
// GROUP:PORT, has a port outside 1…65535 or a ttl outside 0…255.
std::optional<LcmUrl> parse_lcm_url(std::string_view url, std::string* why = nullptr);

// KEY=VALUE lines as systemd's EnvironmentFile= reads them: '#' and ';' comment lines, blank
// lines, "export " prefixes, single or double quotes around the value.
std::map<std::string, std::string> parse_env_file(std::string_view text);

// "239.255.76.67:7667": the udpm group and port a program with this URL sends to and listens on
// ("" = LCM_DEFAULT_URL, else LCM's default, as lcm_create takes it); "" when it is not udpm. Every
// message names it (sent_to): a message heard on a port but sent to another group is another lab's.
std::string lcm_destination(const std::string& url);

struct ResolvedLcmUrl {
  std::string url;
  std::string source;  // "--lcm-url", "LCM_DEFAULT_URL", "/etc/spindown/lcm.env", "LCM's default"
};
// cli: --lcm-url ("" when not given); env: LCM_DEFAULT_URL of this process (nullopt when unset
// or empty); env_file: LCM_DEFAULT_URL of the services' env file (nullopt when none).
ResolvedLcmUrl resolve_lcm_url(const std::string& cli, const std::optional<std::string>& env,
                               const std::optional<std::string>& env_file,
                               std::string_view env_file_path = lcm_env_file_path);

}  // namespace spindown
