#pragma once
// The network checks of `spindown doctor`, as pure functions over what the system shows
// (/proc/net/route, /sys/class/net/*/flags, /proc/sys/net/core/rmem_max, /proc/net/snmp,
// `nft list ruleset`, `iptables-save`), so tests give them fixtures:
//   multicast route  — LCM's udpm sends to a multicast group; without a route for it nothing starts
//   LCM TTL          — ttl=0 stays on this host, ttl=1 reaches the lab LAN
//   receive buffer   — a small net.core.rmem_max drops bursts before LCM reads them
//   firewall         — rules that drop UDP to the LCM port or multicast (read-only)
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "spindown/doctor_check.hpp"
#include "spindown/lcm_url.hpp"

#include "spindown/udp_socket_drops.hpp"

namespace spindown {

// One line of /proc/net/route (the main IPv4 table); addresses in host byte order.
struct Ipv4Route {
  std::string iface;
  std::uint32_t destination = 0;
  std::uint32_t gateway = 0;
  std::uint32_t mask = 0;
  unsigned flags = 0;  // RTF_UP 0x1, RTF_GATEWAY 0x2
  int metric = 0;
  int prefix_length() const;
};

// Lines that do not parse (the header, garbage) are skipped.
std::vector<Ipv4Route> parse_proc_net_route(std::string_view text);
std::optional<std::uint32_t> parse_ipv4(std::string_view dotted);  // host byte order
std::string format_ipv4(std::uint32_t address);
std::string format_route(const Ipv4Route& route);  // "224.0.0.0/4 dev lo", "default via 10.0.0.1 dev eth0"

// The route the kernel's main table takes for address: the longest prefix among routes that
// are up, then the lowest metric. Nullptr when none.
const Ipv4Route* find_route(const std::vector<Ipv4Route>& routes, std::uint32_t address);

struct NetInterface {
  std::string name;
  bool up = false;
  bool loopback = false;
  bool multicast = false;  // IFF_MULTICAST: the interface can send multicast (lo cannot say so, yet works)
};
// From /sys/class/net/NAME/flags ("0x1003"); nullopt when the text is not a number.
std::optional<NetInterface> interface_from_flags(std::string name, std::string_view flags_text);

// Is there a route for the URL's multicast group, on an interface that is up, and does it
// reach the LAN when the TTL asks for it? fail without a route (the fix names lo and the LAN
// interfaces that are up), warn when ttl ≥ 1 but the route goes to lo only.
DoctorCheck check_multicast_route(const LcmUrl& url, const std::vector<Ipv4Route>& routes,
                                  const std::vector<NetInterface>& interfaces);

// ttl=1 ok; ttl=0 warn (this host only) unless single_host; ttl>1 warn (routed beyond the LAN).
// services_url: the services' URL (/etc/spindown/lcm.env) when known: warn when the group or
// port differs from url (this shell and the services would not hear each other).
DoctorCheck check_lcm_ttl(const LcmUrl& url, const std::string& source, bool single_host,
                          const std::optional<std::string>& services_url);

// LCM recommends ≥ 2 MB of socket receive buffer; the services ask for 16 MB (--recv-buf) and the
// kernel caps it at net.core.rmem_max. rcvbuf_errors: Udp RcvbufErrors from /proc/net/snmp.
inline constexpr long lcm_recommended_rmem_bytes = 2L << 20;
DoctorCheck check_receive_buffer(std::optional<long> rmem_max, std::optional<long> rcvbuf_errors);
// Udp RcvbufErrors from the text of /proc/net/snmp.
std::optional<long> parse_udp_rcvbuf_errors(std::string_view proc_net_snmp);

// A process's own UDP sockets' drops: udp_socket_drops.hpp (bus).

// The firewall as `nft list ruleset` and/or `iptables-save` print it (nullopt: not available;
// unreadable is the caller's skip). fail: a rule that drops or rejects the LCM port, the group,
// 224.0.0.0/4, multicast, all UDP or everything, before any rule accepting LCM; warn: a chain
// whose policy is drop with no rule accepting LCM. Rules are matched by reading their text, so
// unusual rule sets are reported as what they look like, with the rule quoted.
DoctorCheck check_firewall(const LcmUrl& url, const std::optional<std::string>& nft_ruleset,
                           const std::optional<std::string>& iptables_save);

}  // namespace spindown
