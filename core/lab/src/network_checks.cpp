#include "spindown/network_checks.hpp"
#include "spindown/trim.hpp"

#include <algorithm>
#include <arpa/inet.h>
#include <cctype>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <fmt/format.h>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace spindown {

namespace {

std::vector<std::string_view> split_lines(std::string_view text) {
  std::vector<std::string_view> out;
  while (!text.empty()) {
    const auto nl = text.find('\n');
    out.push_back(text.substr(0, nl));
    if (nl == std::string_view::npos) break;
    text = text.substr(nl + 1);
  }
  return out;
}

std::vector<std::string> words(std::string_view line) {
  std::vector<std::string> out;
  std::istringstream in{std::string(line)};
  std::string w;
  while (in >> w) out.push_back(w);
  return out;
}

bool parse_hex32(std::string_view s, std::uint32_t& out) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out, 16);
  return ec == std::errc() && p == s.data() + s.size() && !s.empty();
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

bool is_multicast(std::uint32_t address) { return (address >> 28) == 0xE; }

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

}  // namespace

// ---- routes -----------------------------------------------------------------------------------

int Ipv4Route::prefix_length() const {
  int n = 0;
  for (std::uint32_t m = mask; m & 0x80000000u; m <<= 1) ++n;
  return n;
}

std::vector<Ipv4Route> parse_proc_net_route(std::string_view text) {
  std::vector<Ipv4Route> routes;
  for (const auto line : split_lines(text)) {
    const auto w = words(line);
    // Iface Destination Gateway Flags RefCnt Use Metric Mask MTU Window IRTT
    if (w.size() < 8) continue;
    std::uint32_t dest = 0, gw = 0, flags = 0, mask = 0;
    if (!parse_hex32(w[1], dest) || !parse_hex32(w[2], gw) || !parse_hex32(w[3], flags) || !parse_hex32(w[7], mask))
      continue;  // the header, or garbage
    Ipv4Route r;
    r.iface = w[0];
    // The kernel prints the network-order word as a host integer.
    r.destination = ntohl(dest);
    r.gateway = ntohl(gw);
    r.mask = ntohl(mask);
    r.flags = flags;
    r.metric = std::atoi(w[6].c_str());
    routes.push_back(r);
  }
  return routes;
}

std::optional<std::uint32_t> parse_ipv4(std::string_view dotted) {
  const std::string s(dotted);
  in_addr a{};
  if (::inet_pton(AF_INET, s.c_str(), &a) != 1) return std::nullopt;
  return ntohl(a.s_addr);
}

std::string format_ipv4(std::uint32_t address) {
  return fmt::format("{}.{}.{}.{}", address >> 24, (address >> 16) & 0xFF, (address >> 8) & 0xFF, address & 0xFF);
}

std::string format_route(const Ipv4Route& r) {
  std::string dest = r.mask == 0 ? "default" : fmt::format("{}/{}", format_ipv4(r.destination), r.prefix_length());
  if (r.flags & 0x2) dest += " via " + format_ipv4(r.gateway);
  return dest + " dev " + r.iface;
}

const Ipv4Route* find_route(const std::vector<Ipv4Route>& routes, std::uint32_t address) {
  const Ipv4Route* best = nullptr;
  for (const auto& r : routes) {
    if (!(r.flags & 0x1)) continue;  // not up
    if ((address & r.mask) != (r.destination & r.mask)) continue;
    if (!best || r.prefix_length() > best->prefix_length() ||
        (r.prefix_length() == best->prefix_length() && r.metric < best->metric))
      best = &r;
  }
  return best;
}

std::optional<NetInterface> interface_from_flags(std::string name, std::string_view flags_text) {
  std::string_view t = trim(flags_text);
  if (t.rfind("0x", 0) == 0 || t.rfind("0X", 0) == 0) t.remove_prefix(2);
  std::uint32_t flags = 0;
  if (!parse_hex32(t, flags)) return std::nullopt;
  NetInterface i;
  i.name = std::move(name);
  i.up = flags & 0x1;          // IFF_UP
  i.loopback = flags & 0x8;    // IFF_LOOPBACK
  i.multicast = flags & 0x1000;  // IFF_MULTICAST
  return i;
}

DoctorCheck check_multicast_route(const LcmUrl& url, const std::vector<Ipv4Route>& routes,
                                  const std::vector<NetInterface>& interfaces) {
  DoctorCheck c{"multicast route", CheckLevel::ok, "", ""};
  if (url.provider != "udpm") {
    c.level = CheckLevel::skip;
    c.detail = fmt::format("LCM URL is {}://, not multicast", url.provider);
    return c;
  }
  const auto group = parse_ipv4(url.address);
  if (!group || !is_multicast(*group)) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("'{}' in the LCM URL is not an IPv4 multicast group (224.0.0.0 … 239.255.255.255)", url.address);
    c.fix = "LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1 in /etc/spindown/lcm.env";
    return c;
  }
  std::vector<std::string> lan;
  for (const auto& i : interfaces)
    if (i.up && !i.loopback) lan.push_back(i.name);
  const std::string lan_text = lan.empty() ? "the lab LAN's interface (none is up: ip link)" : join(lan, " or ");
  const std::string lan_fix = fmt::format("ip route add 224.0.0.0/4 dev {}   # the lab LAN ({}: the interface on the lab's switch)",
                                          lan.size() == 1 ? lan.front() : "IFACE", lan_text);
  const std::string lo_fix = "ip route add 224.0.0.0/4 dev lo     # this host only (LCM ttl=0)";
  const Ipv4Route* r = find_route(routes, *group);
  if (!r) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("no route for {}: LCM cannot send or join the group, so no spindown program starts on {}",
                           url.address, url.text);
    c.fix = url.ttl == 0 ? lo_fix + "\n" + lan_fix : lan_fix + "\n" + lo_fix;
    return c;
  }
  const auto iface = std::find_if(interfaces.begin(), interfaces.end(), [&](const NetInterface& i) { return i.name == r->iface; });
  const bool loopback = r->iface == "lo" || (iface != interfaces.end() && iface->loopback);
  if (iface != interfaces.end() && !iface->up) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("{} goes to {} ({}), which is down", url.address, r->iface, format_route(*r));
    c.fix = fmt::format("ip link set {} up", r->iface);
    return c;
  }
  if (loopback && url.ttl >= 1) {
    c.level = CheckLevel::warn;
    c.detail = fmt::format("{} goes to lo only ({}): LCM ttl={} is meant for the lab LAN, but other lab PCs hear nothing",
                           url.address, format_route(*r), url.ttl);
    c.fix = fmt::format("ip route replace 224.0.0.0/4 dev {}   # the lab LAN ({})", lan.size() == 1 ? lan.front() : "IFACE",
                        lan_text);
    return c;
  }
  if (r->mask == 0) {
    c.detail = fmt::format("{} follows the default route ({}); if the lab LAN is another interface: "
                           "ip route add 224.0.0.0/4 dev IFACE",
                           url.address, format_route(*r));
    return c;
  }
  c.detail = fmt::format("{} goes out on {} ({})", url.address, r->iface, format_route(*r));
  return c;
}

// ---- TTL -----------------------------------------------------------------------------------------

DoctorCheck check_lcm_ttl(const LcmUrl& url, const std::string& source, bool single_host,
                          const std::optional<std::string>& services_url) {
  DoctorCheck c{"LCM TTL", CheckLevel::ok, "", ""};
  if (url.provider != "udpm") {
    c.level = CheckLevel::skip;
    c.detail = fmt::format("{} (from {}) is not multicast", url.text, source);
    return c;
  }
  const std::string lab_url = fmt::format("udpm://{}:{}?ttl=1", url.address, url.port);
  if (url.ttl == 0) {
    c.detail = fmt::format("{} (from {}): ttl=0, messages stay on this host", url.text, source);
    if (single_host) {
      c.detail += " (--single-host: the whole lab runs here)";
    } else {
      c.level = CheckLevel::warn;
      c.detail += "; bridges, fitter and logger on other lab PCs hear nothing";
      c.fix = fmt::format("LCM_DEFAULT_URL={} in /etc/spindown/lcm.env on every lab PC; in a shell: set -a; . /etc/spindown/lcm.env; set +a",
                          lab_url);
    }
  } else if (url.ttl == 1) {
    c.detail = fmt::format("{} (from {}): ttl=1, the lab LAN segment (routers do not pass it on)", url.text, source);
  } else {
    c.level = CheckLevel::warn;
    c.detail = fmt::format("{} (from {}): ttl={}, multicast routers may carry the lab's traffic beyond the lab LAN",
                           url.text, source, url.ttl);
    c.fix = fmt::format("LCM_DEFAULT_URL={} in /etc/spindown/lcm.env", lab_url);
  }
  if (services_url) {
    const auto svc = parse_lcm_url(*services_url);
    if (svc && (svc->provider != url.provider || svc->address != url.address || svc->port != url.port)) {
      c.level = std::max(c.level, CheckLevel::warn);
      c.detail += fmt::format("; but the services use {} ({}): they and this shell do not hear each other", *services_url,
                              lcm_env_file_path);
      if (!c.fix.empty()) c.fix += "\n";
      c.fix += "set -a; . /etc/spindown/lcm.env; set +a   # this shell on the services' URL";
    }
  }
  return c;
}

// ---- receive buffer ----------------------------------------------------------------------------

std::optional<long> parse_udp_rcvbuf_errors(std::string_view text) {
  const auto lines = split_lines(text);
  for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
    if (lines[i].rfind("Udp:", 0) != 0 || lines[i + 1].rfind("Udp:", 0) != 0) continue;
    const auto names = words(lines[i].substr(4));
    const auto values = words(lines[i + 1].substr(4));
    for (std::size_t k = 0; k < names.size() && k < values.size(); ++k)
      if (names[k] == "RcvbufErrors") return std::atol(values[k].c_str());
    return std::nullopt;
  }
  return std::nullopt;
}

DoctorCheck check_receive_buffer(std::optional<long> rmem_max, std::optional<long> rcvbuf_errors) {
  DoctorCheck c{"receive buffer", CheckLevel::ok, "", ""};
  const std::string errors =
      rcvbuf_errors ? fmt::format("; {} UDP datagrams dropped for a full receive buffer since boot (all sockets)", *rcvbuf_errors)
                    : "";
  if (!rmem_max) {
    c.level = CheckLevel::skip;
    c.detail = "cannot read /proc/sys/net/core/rmem_max" + errors;
    return c;
  }
  const double mb = double(*rmem_max) / (1 << 20);
  if (*rmem_max < lcm_recommended_rmem_bytes) {
    c.level = CheckLevel::warn;
    c.detail = fmt::format("net.core.rmem_max = {} ({:.2g} MB), below LCM's recommended 2 MB: a burst from many benches "
                           "is dropped by the kernel before LCM reads it{}",
                           *rmem_max, mb, errors);
    c.fix = fmt::format("sysctl -w net.core.rmem_max={0}\necho 'net.core.rmem_max = {0}' > /etc/sysctl.d/60-spindown.conf   # at every boot",
                        services_recv_buf_bytes);
    return c;
  }
  c.detail = fmt::format("net.core.rmem_max = {} ({:.3g} MB) ≥ LCM's recommended 2 MB{}{}", *rmem_max, mb,
                         *rmem_max < services_recv_buf_bytes
                             ? fmt::format(" (the services ask for {} MB and get this: a full-speed burst can "
                                           "overflow it; `sysctl -w net.core.rmem_max={}` gives them all of it)",
                                           services_recv_buf_bytes >> 20, services_recv_buf_bytes)
                             : "",
                         errors);
  return c;
}

// ---- firewall ------------------------------------------------------------------------------------

namespace {

enum class Verdict { none, accept, drop };

struct RuleFacts {
  Verdict verdict = Verdict::none;
  bool mentions_lcm = false;  // the port, the group, 224.0.0.0/4 or multicast
  bool catch_all = false;     // no match beyond "udp" (and counters, logs, comments)
};

// Reads a rule's text (nft or iptables-save syntax): its verdict, whether it names LCM's traffic
// and whether it matches everything (or all UDP).
RuleFacts read_rule(std::string_view rule, const LcmUrl& url) {
  RuleFacts f;
  // Words, with a quoted string ("allow lcm") kept as one.
  std::vector<std::string> w;
  for (auto& s : words(rule)) {
    if (!w.empty() && w.back().size() > 0 && w.back().front() == '"' &&
        (w.back().size() == 1 || w.back().back() != '"'))
      w.back() += " " + s;
    else
      w.push_back(s);
  }
  // Tokens without punctuation, lower case: "{ 5353, 7667 }" -> 5353 7667.
  std::vector<std::string> t;
  for (auto& s : w) {
    std::string x = lower(s);
    while (!x.empty() && (x.back() == ',' || x.back() == '}' || x.back() == ';')) x.pop_back();
    while (!x.empty() && x.front() == '{') x.erase(0, 1);
    if (!x.empty()) t.push_back(x);
  }
  const std::string port = std::to_string(url.port);
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const std::string& x = t[i];
    if (x == "accept") { f.verdict = Verdict::accept; continue; }
    if (x == "drop" || x == "reject") { f.verdict = Verdict::drop; continue; }
    if (x == "-j" && i + 1 < t.size()) {
      const std::string& v = t[++i];
      if (v == "accept") f.verdict = Verdict::accept;
      else if (v == "drop" || v == "reject") f.verdict = Verdict::drop;
      else rest.push_back(v);  // a jump to another chain: not a catch-all verdict
      continue;
    }
    if (x == port || x == url.address || x == url.address + "/32" || x == "224.0.0.0/4" || x == "multicast")
      f.mentions_lcm = true;
    // What restricts nothing (for UDP): counters, logs, comments, the table's chain name, "udp".
    if (x == "counter" || x == "udp" || x == "meta" || x == "l4proto" || x == "ip" || x == "protocol" || x == "-p" ||
        x == "-m" || x == "tcp-reset" || x == "with" || x == "icmp" || x == "icmpx" || x == "type" ||
        x.find_first_not_of("0123456789") == std::string::npos)
      continue;
    if (x == "packets" || x == "bytes") { ++i; continue; }
    if ((x == "-a" || x == "comment" || x == "--comment" || x == "prefix" || x == "--log-prefix") && i + 1 < t.size()) {
      ++i;
      continue;
    }
    if (x == "log" || x == "reject-with" || x == "--reject-with") continue;
    if (x.find("unreachable") != std::string::npos || x.find("prohibited") != std::string::npos) continue;
    rest.push_back(x);
  }
  f.catch_all = rest.empty();
  return f;
}

struct Chain {
  std::string family_table;  // "inet filter" (nft) or "filter" (iptables)
  std::string name;
  std::string hook;          // nft: input/output/prerouting/…; iptables: INPUT/OUTPUT/… lower-cased
  bool policy_drop = false;
  std::vector<std::string> rules;
};

std::vector<Chain> parse_nft(std::string_view text) {
  std::vector<Chain> chains;
  enum class Kind { table, chain, other };
  struct Block { Kind kind; int inner = 0; };
  std::vector<Block> stack;
  std::string table;
  for (const auto raw : split_lines(text)) {
    std::string_view line = trim(raw);
    if (const auto h = line.find(" # handle "); h != std::string_view::npos) line = trim(line.substr(0, h));
    if (line.empty()) continue;
    const int net = static_cast<int>(std::count(line.begin(), line.end(), '{') - std::count(line.begin(), line.end(), '}'));
    const bool opens = line.back() == '{';
    if (!stack.empty() && stack.back().kind == Kind::other) {
      if (opens && net > 0 && stack.back().inner == 0 && line.find('=') == std::string_view::npos) {
        stack.push_back({Kind::other, 0});
        continue;
      }
      stack.back().inner += net;
      if (stack.back().inner < 0) stack.pop_back();
      continue;
    }
    if (opens && line.rfind("table ", 0) == 0) {
      const auto w = words(line.substr(6));
      table = w.size() >= 3 ? w[0] + " " + w[1] : (w.empty() ? "" : "ip " + w[0]);
      stack.push_back({Kind::table, 0});
      continue;
    }
    if (opens && line.rfind("chain ", 0) == 0) {
      const auto w = words(line.substr(6));
      chains.push_back({table, w.empty() ? "?" : w[0], "", false, {}});
      stack.push_back({Kind::chain, 0});
      continue;
    }
    if (opens && net > 0) {  // set, map, flowtable, counter…: skipped
      stack.push_back({Kind::other, 0});
      continue;
    }
    if (line == "}") {
      if (!stack.empty()) stack.pop_back();
      continue;
    }
    if (stack.empty() || stack.back().kind != Kind::chain || chains.empty()) continue;
    Chain& c = chains.back();
    if (line.find(" hook ") != std::string_view::npos || line.rfind("type ", 0) == 0) {
      const auto w = words(line);
      for (std::size_t i = 0; i + 1 < w.size(); ++i) {
        std::string v = w[i + 1];
        while (!v.empty() && v.back() == ';') v.pop_back();
        if (w[i] == "hook") c.hook = v;
        if (w[i] == "policy") c.policy_drop = v == "drop";
      }
      continue;
    }
    c.rules.emplace_back(line);
  }
  return chains;
}

std::vector<Chain> parse_iptables_save(std::string_view text) {
  std::vector<Chain> chains;
  std::string table;
  auto chain_named = [&](const std::string& name) -> Chain& {
    for (auto& c : chains)
      if (c.family_table == table && c.name == name) return c;
    const bool builtin = name == "INPUT" || name == "OUTPUT" || name == "PREROUTING" || name == "FORWARD" ||
                         name == "POSTROUTING";
    chains.push_back({table, name, builtin ? lower(name) : "", false, {}});
    return chains.back();
  };
  for (const auto raw : split_lines(text)) {
    const std::string_view line = trim(raw);
    if (line.empty() || line.front() == '#') continue;
    if (line.front() == '*') {
      table = std::string(line.substr(1));
      continue;
    }
    if (line.front() == ':') {
      const auto w = words(line.substr(1));
      if (w.empty()) continue;
      chain_named(w[0]).policy_drop = w.size() > 1 && w[1] == "DROP";
      continue;
    }
    if (line.rfind("-A ", 0) == 0) {
      const auto w = words(line);
      if (w.size() >= 2) chain_named(w[1]).rules.emplace_back(line);
    }
  }
  return chains;
}

struct FirewallFinding {
  CheckLevel level;
  std::string text;
  std::string fix;
};

void analyze(const std::vector<Chain>& chains, const LcmUrl& url, bool nft, std::vector<FirewallFinding>& out) {
  const std::string accept_rule =
      nft ? fmt::format("ip daddr 224.0.0.0/4 udp dport {} accept", url.port)
          : fmt::format("-p udp -d 224.0.0.0/4 --dport {} -j ACCEPT", url.port);
  for (const auto& c : chains) {
    const bool base = c.hook == "input" || c.hook == "output" || c.hook == "prerouting";
    if (!nft && c.family_table == "nat") continue;
    const std::string where = nft ? fmt::format("nft {} chain {}", c.family_table, c.name)
                                  : fmt::format("iptables -t {} {}", c.family_table, c.name);
    const std::string fix = nft ? fmt::format("nft insert rule {} {} {}   # before the rule that drops it", c.family_table,
                                              c.name, accept_rule)
                                : fmt::format("iptables -t {} -I {} {}", c.family_table, c.name, accept_rule);
    bool decided = false;
    for (const auto& rule : c.rules) {
      const RuleFacts f = read_rule(rule, url);
      if (f.verdict == Verdict::none) continue;
      const bool about_lcm = f.mentions_lcm || (base && f.catch_all);
      if (!about_lcm) continue;
      if (f.verdict == Verdict::accept) {
        decided = true;
        break;
      }
      out.push_back({CheckLevel::fail, fmt::format("{} drops LCM traffic: '{}'", where, rule), fix});
      decided = true;
      break;
    }
    if (!decided && base && c.policy_drop)
      out.push_back({CheckLevel::warn,
                     fmt::format("{} drops by policy and no rule accepts UDP {} to {} (multicast from other lab PCs is "
                                 "dropped unless a rule accepts it)",
                                 where, url.port, url.address),
                     fix});
  }
}

}  // namespace

DoctorCheck check_firewall(const LcmUrl& url, const std::optional<std::string>& nft_ruleset,
                           const std::optional<std::string>& iptables_save) {
  DoctorCheck c{"firewall", CheckLevel::ok, "", ""};
  if (url.provider != "udpm") {
    c.level = CheckLevel::skip;
    c.detail = fmt::format("LCM URL is {}://, not UDP", url.provider);
    return c;
  }
  if (!nft_ruleset && !iptables_save) {
    c.level = CheckLevel::skip;
    c.detail = "neither nft nor iptables-save is available: no firewall rules to read";
    return c;
  }
  std::vector<FirewallFinding> findings;
  std::size_t rules = 0;
  if (nft_ruleset) {
    const auto chains = parse_nft(*nft_ruleset);
    for (const auto& ch : chains) rules += ch.rules.size();
    analyze(chains, url, true, findings);
  }
  if (iptables_save) {
    const auto chains = parse_iptables_save(*iptables_save);
    for (const auto& ch : chains) rules += ch.rules.size();
    analyze(chains, url, false, findings);
  }
  const std::string what = nft_ruleset && iptables_save ? "nft and iptables" : nft_ruleset ? "nft" : "iptables";
  if (findings.empty()) {
    c.detail = fmt::format("{} rule{} ({}): nothing drops UDP {} to {}", rules, rules == 1 ? "" : "s", what, url.port,
                           url.address);
    return c;
  }
  std::vector<std::string> texts, fixes;
  for (const auto& f : findings) {
    c.level = std::max(c.level, f.level);
    texts.push_back(f.text);
    if (std::find(fixes.begin(), fixes.end(), f.fix) == fixes.end()) fixes.push_back(f.fix);
  }
  c.detail = join(texts, "; ");
  c.fix = join(fixes, "\n");
  return c;
}

}  // namespace spindown
