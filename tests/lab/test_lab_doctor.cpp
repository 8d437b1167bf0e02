// spindown doctor's checks over fixtures: /proc/net/route, interface flags, rmem_max and
// /proc/net/snmp, nft and iptables rule sets, LCM URLs and env files, a sysfs tty tree with USB
// serial numbers, device permissions, bench files, clock state and clock skew; the report's
// text, JSON and exit code; and the LCM self-test over memq://.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "spindown/clock_checks.hpp"
#include "spindown/doctor_check.hpp"
#include "spindown/lcm_self_test.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/network_checks.hpp"
#include "spindown/serial_inventory.hpp"

namespace fs = std::filesystem;
using namespace spindown;

namespace {

// /proc/net/route of a lab PC: default via 192.168.1.1 on eth0, the LAN on eth0, and an
// explicit multicast route on eth1 (hex words as a little-endian kernel prints them).
const char* const kRouteLab =
    "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n"
    "eth0\t00000000\t0101A8C0\t0003\t0\t0\t100\t00000000\t0\t0\t0\n"
    "eth0\t0001A8C0\t00000000\t0001\t0\t0\t100\t00FFFFFF\t0\t0\t0\n"
    "eth1\t000000E0\t00000000\t0001\t0\t0\t0\t000000F0\t0\t0\t0\n";
const char* const kRouteDefaultOnly =
    "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n"
    "wlan0\t00000000\t0101A8C0\t0003\t0\t0\t600\t00000000\t0\t0\t0\n";
const char* const kRouteLoOnly =
    "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n"
    "lo\t000000E0\t00000000\t0001\t0\t0\t0\t000000F0\t0\t0\t0\n";
const char* const kRouteEmpty = "Iface\tDestination\tGateway \tFlags\tRefCnt\tUse\tMetric\tMask\t\tMTU\tWindow\tIRTT\n";

LcmUrl url_of(const std::string& text) {
  std::string why;
  auto u = parse_lcm_url(text, &why);
  EXPECT_TRUE(u.has_value()) << why;
  return u.value_or(LcmUrl{});
}

std::vector<NetInterface> interfaces(std::initializer_list<std::pair<const char*, const char*>> flags) {
  std::vector<NetInterface> out;
  for (const auto& [name, f] : flags) out.push_back(*interface_from_flags(name, f));
  return out;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

struct TempDir {
  fs::path path;
  TempDir() {
    char tmpl[] = "/tmp/test_lab_doctor.XXXXXX";
    path = ::mkdtemp(tmpl);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

void write(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

}  // namespace

// ---- routes ----------------------------------------------------------------------------------

TEST(ProcNetRoute, ParsesAddressesMasksAndSkipsTheHeader) {
  const auto routes = parse_proc_net_route(kRouteLab);
  ASSERT_EQ(routes.size(), 3u);
  EXPECT_EQ(routes[0].iface, "eth0");
  EXPECT_EQ(format_route(routes[0]), "default via 192.168.1.1 dev eth0");
  EXPECT_EQ(format_route(routes[1]), "192.168.1.0/24 dev eth0");
  EXPECT_EQ(format_route(routes[2]), "224.0.0.0/4 dev eth1");
  EXPECT_EQ(routes[2].prefix_length(), 4);
  EXPECT_TRUE(parse_proc_net_route("garbage\n\n1 2 3\n").empty());
}

TEST(ProcNetRoute, LongestPrefixWins) {
  const auto routes = parse_proc_net_route(kRouteLab);
  const auto* r = find_route(routes, *parse_ipv4("239.255.76.67"));
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->iface, "eth1");
  const auto* lan = find_route(routes, *parse_ipv4("192.168.1.20"));
  ASSERT_NE(lan, nullptr);
  EXPECT_EQ(format_route(*lan), "192.168.1.0/24 dev eth0");
  EXPECT_EQ(find_route(parse_proc_net_route(kRouteEmpty), *parse_ipv4("239.255.76.67")), nullptr);
}

TEST(InterfaceFlags, UpLoopbackMulticast) {
  const auto lo = interface_from_flags("lo", "0x9\n");
  ASSERT_TRUE(lo);
  EXPECT_TRUE(lo->up);
  EXPECT_TRUE(lo->loopback);
  const auto eth = interface_from_flags("eth0", "0x1003");
  ASSERT_TRUE(eth);
  EXPECT_TRUE(eth->up && eth->multicast && !eth->loopback);
  const auto down = interface_from_flags("eth1", "0x1002");
  EXPECT_FALSE(down->up);
  EXPECT_FALSE(interface_from_flags("x", "bogus"));
}

TEST(MulticastRoute, NoRouteFailsAndNamesLoAndTheLanInterface) {
  const auto c = check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=0"), parse_proc_net_route(kRouteEmpty),
                                       interfaces({{"lo", "0x9"}, {"eth0", "0x1003"}}));
  EXPECT_EQ(c.level, CheckLevel::fail);
  EXPECT_TRUE(contains(c.detail, "no route for 239.255.76.67")) << c.detail;
  EXPECT_TRUE(contains(c.fix, "ip route add 224.0.0.0/4 dev lo")) << c.fix;
  EXPECT_TRUE(contains(c.fix, "ip route add 224.0.0.0/4 dev eth0")) << c.fix;
}

TEST(MulticastRoute, ExplicitRouteIsOk) {
  const auto c = check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=1"), parse_proc_net_route(kRouteLab),
                                       interfaces({{"lo", "0x9"}, {"eth0", "0x1003"}, {"eth1", "0x1003"}}));
  EXPECT_EQ(c.level, CheckLevel::ok);
  EXPECT_TRUE(contains(c.detail, "eth1")) << c.detail;
}

TEST(MulticastRoute, DefaultRouteIsOkAndSaysSo) {
  const auto c = check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=1"), parse_proc_net_route(kRouteDefaultOnly),
                                       interfaces({{"lo", "0x9"}, {"wlan0", "0x1003"}}));
  EXPECT_EQ(c.level, CheckLevel::ok);
  EXPECT_TRUE(contains(c.detail, "default route")) << c.detail;
}

TEST(MulticastRoute, LoopbackOnlyWithTtl1Warns) {
  const auto routes = parse_proc_net_route(kRouteLoOnly);
  const auto ifs = interfaces({{"lo", "0x9"}, {"eth0", "0x1003"}});
  EXPECT_EQ(check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=0"), routes, ifs).level, CheckLevel::ok);
  const auto c = check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=1"), routes, ifs);
  EXPECT_EQ(c.level, CheckLevel::warn);
  EXPECT_TRUE(contains(c.fix, "dev eth0")) << c.fix;
}

TEST(MulticastRoute, RouteOnADownInterfaceFails) {
  const auto c = check_multicast_route(url_of("udpm://239.255.76.67:7667?ttl=1"), parse_proc_net_route(kRouteLab),
                                       interfaces({{"eth0", "0x1003"}, {"eth1", "0x1002"}}));
  EXPECT_EQ(c.level, CheckLevel::fail);
  EXPECT_EQ(c.fix, "ip link set eth1 up");
}

TEST(MulticastRoute, NotMulticastIsSkippedOrFailed) {
  EXPECT_EQ(check_multicast_route(url_of("memq://"), {}, {}).level, CheckLevel::skip);
  EXPECT_EQ(check_multicast_route(url_of("udpm://10.0.0.1:7667"), parse_proc_net_route(kRouteLab), {}).level,
            CheckLevel::fail);
}

// ---- LCM URL, env file, TTL ------------------------------------------------------------------

TEST(LcmUrl, ParsesUdpmAndRejectsNonsense) {
  const auto u = url_of("udpm://239.255.76.67:7667?ttl=1&recv_buf_size=4194304");
  EXPECT_EQ(u.provider, "udpm");
  EXPECT_EQ(u.address, "239.255.76.67");
  EXPECT_EQ(u.port, 7667);
  EXPECT_EQ(u.ttl, 1);
  EXPECT_TRUE(u.ttl_given);
  EXPECT_EQ(u.recv_buf_size, 4194304);
  const auto d = url_of("udpm://");
  EXPECT_EQ(d.port, 7667);
  EXPECT_EQ(d.ttl, 0);
  std::string why;
  EXPECT_FALSE(parse_lcm_url("239.255.76.67:7667", &why));
  EXPECT_TRUE(contains(why, "PROVIDER://")) << why;
  EXPECT_FALSE(parse_lcm_url("udpm://239.255.76.67:99999", &why));
  EXPECT_TRUE(contains(why, "99999")) << why;
  EXPECT_FALSE(parse_lcm_url("udpm://239.255.76.67:7667?ttl=300", &why));
  EXPECT_FALSE(parse_lcm_url("udpm://239.255.76.67:7667?ttl", &why));
}

TEST(LcmUrl, EnvFileAndResolutionOrder) {
  const auto env = parse_env_file(
      "# comment\n; another\n\nexport LCM_DEFAULT_URL=\"udpm://239.255.76.67:7667?ttl=1\"\nOTHER='x y'\nbroken line\n");
  ASSERT_EQ(env.count("LCM_DEFAULT_URL"), 1u);
  EXPECT_EQ(env.at("LCM_DEFAULT_URL"), "udpm://239.255.76.67:7667?ttl=1");
  EXPECT_EQ(env.at("OTHER"), "x y");
  EXPECT_EQ(env.size(), 2u);
  EXPECT_EQ(resolve_lcm_url("memq://", "a://", "b://").source, "--lcm-url");
  EXPECT_EQ(resolve_lcm_url("", "a://", "b://").url, "a://");
  EXPECT_EQ(resolve_lcm_url("", std::nullopt, "b://").source, "/etc/spindown/lcm.env");
  EXPECT_EQ(resolve_lcm_url("", std::nullopt, std::nullopt).url, "udpm://239.255.76.67:7667?ttl=0");
}

// The services' receive buffer goes into a udpm URL that does not set one, and nowhere else.
TEST(LcmUrl, ReceiveBufferIsAddedOnlyWhereItBelongs) {
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667?ttl=1", services_recv_buf_bytes),
            "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=16777216");
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667", 1000), "udpm://239.255.76.67:7667?recv_buf_size=1000");
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667?recv_buf_size=5", 1000),
            "udpm://239.255.76.67:7667?recv_buf_size=5");  // the URL's own wins
  EXPECT_EQ(with_receive_buffer("memq://", 1000), "memq://");
  EXPECT_EQ(with_receive_buffer("udpm://239.255.76.67:7667?ttl=1", 0), "udpm://239.255.76.67:7667?ttl=1");
  const char* before = std::getenv("LCM_DEFAULT_URL");
  const std::string saved = before ? before : "";
  ::setenv("LCM_DEFAULT_URL", "udpm://239.255.76.70:7700?ttl=0", 1);
  EXPECT_EQ(with_receive_buffer("", 1000), "udpm://239.255.76.70:7700?ttl=0&recv_buf_size=1000");
  ::unsetenv("LCM_DEFAULT_URL");
  EXPECT_EQ(with_receive_buffer("", 1000), "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=1000");
  if (before) ::setenv("LCM_DEFAULT_URL", saved.c_str(), 1);
}

// The limit install-lab ships is the buffer the services ask for: the two cannot drift apart.
TEST(ReceiveBuffer, ShippedSysctlGivesTheServicesWhatTheyAskFor) {
  std::ifstream conf(std::string(SPINDOWN_SOURCE_DIR) + "/deploy/sysctl/60-spindown.conf");
  ASSERT_TRUE(conf) << "deploy/sysctl/60-spindown.conf";
  long value = -1;
  for (std::string line; std::getline(conf, line);)
    if (line.rfind("net.core.rmem_max", 0) == 0) value = std::stol(line.substr(line.find('=') + 1));
  EXPECT_EQ(value, services_recv_buf_bytes);
  EXPECT_EQ(check_receive_buffer(value, 0).level, CheckLevel::ok);
  EXPECT_FALSE(contains(check_receive_buffer(value, 0).detail, "ask for")) << "nothing more to give them";
}

TEST(LcmTtl, ZeroWarnsUnlessSingleHostOneIsOkMoreWarns) {
  const auto zero = check_lcm_ttl(url_of("udpm://239.255.76.67:7667?ttl=0"), "LCM's default", false, std::nullopt);
  EXPECT_EQ(zero.level, CheckLevel::warn);
  EXPECT_TRUE(contains(zero.fix, "ttl=1")) << zero.fix;
  EXPECT_EQ(check_lcm_ttl(url_of("udpm://239.255.76.67:7667?ttl=0"), "x", true, std::nullopt).level, CheckLevel::ok);
  EXPECT_EQ(check_lcm_ttl(url_of("udpm://239.255.76.67:7667?ttl=1"), "x", false, std::nullopt).level, CheckLevel::ok);
  EXPECT_EQ(check_lcm_ttl(url_of("udpm://239.255.76.67:7667?ttl=5"), "x", false, std::nullopt).level, CheckLevel::warn);
}

TEST(LcmTtl, ShellAndServicesOnDifferentGroupsWarn) {
  const auto c = check_lcm_ttl(url_of("udpm://239.255.76.68:7668?ttl=1"), "LCM_DEFAULT_URL", false,
                               std::string("udpm://239.255.76.67:7667?ttl=1"));
  EXPECT_EQ(c.level, CheckLevel::warn);
  EXPECT_TRUE(contains(c.detail, "do not hear each other")) << c.detail;
  // Only the TTL differs: same group and port, they hear each other on this host.
  EXPECT_EQ(check_lcm_ttl(url_of("udpm://239.255.76.67:7667?ttl=1"), "x", false,
                          std::string("udpm://239.255.76.67:7667?ttl=1&recv_buf_size=1"))
                .level,
            CheckLevel::ok);
}

// ---- receive buffer ----------------------------------------------------------------------------

TEST(ReceiveBuffer, BelowTwoMegabytesWarnsWithTheSysctl) {
  const auto small = check_receive_buffer(212992, 17);
  EXPECT_EQ(small.level, CheckLevel::warn);
  EXPECT_TRUE(contains(small.fix, "sysctl -w net.core.rmem_max=16777216")) << small.fix;
  EXPECT_TRUE(contains(small.detail, "17 UDP datagrams dropped")) << small.detail;
  EXPECT_EQ(check_receive_buffer(2097152, 0).level, CheckLevel::ok);
  // Enough for LCM, less than the services ask for: ok, and the detail says how to give them all.
  const auto between = check_receive_buffer(8388608, std::nullopt);
  EXPECT_EQ(between.level, CheckLevel::ok);
  EXPECT_TRUE(contains(between.detail, "ask for 16 MB and get this")) << between.detail;
  EXPECT_TRUE(contains(between.detail, "sysctl -w net.core.rmem_max=16777216")) << between.detail;
  EXPECT_EQ(check_receive_buffer(std::nullopt, std::nullopt).level, CheckLevel::skip);
}

TEST(ReceiveBuffer, ParsesRcvbufErrorsFromProcNetSnmp) {
  const char* snmp =
      "Ip: Forwarding DefaultTTL\nIp: 1 64\n"
      "Udp: InDatagrams NoPorts InErrors OutDatagrams RcvbufErrors SndbufErrors InCsumErrors IgnoredMulti MemErrors\n"
      "Udp: 1000 3 12 900 12 0 0 5 0\n"
      "UdpLite: InDatagrams NoPorts InErrors OutDatagrams RcvbufErrors SndbufErrors\nUdpLite: 0 0 0 0 99 0\n";
  EXPECT_EQ(parse_udp_rcvbuf_errors(snmp), 12);
  EXPECT_EQ(parse_udp_rcvbuf_errors("nothing here"), std::nullopt);
}

// ---- firewall -----------------------------------------------------------------------------------

TEST(Firewall, EmptyAndAcceptingRuleSetsAreOk) {
  const auto url = url_of("udpm://239.255.76.67:7667?ttl=1");
  EXPECT_EQ(check_firewall(url, std::string(""), std::nullopt).level, CheckLevel::ok);
  // Debian's /etc/nftables.conf: chains with policy accept, no rules.
  const std::string debian =
      "table inet filter {\n\tchain input {\n\t\ttype filter hook input priority filter; policy accept;\n\t}\n"
      "\tchain forward {\n\t\ttype filter hook forward priority filter; policy accept;\n\t}\n"
      "\tchain output {\n\t\ttype filter hook output priority filter; policy accept;\n\t}\n}\n";
  EXPECT_EQ(check_firewall(url, debian, std::nullopt).level, CheckLevel::ok);
  // Policy drop, but LCM accepted first (with a named set that spans lines).
  const std::string guarded =
      "table inet filter {\n\tset lab_hosts {\n\t\ttype ipv4_addr\n\t\telements = { 10.0.0.1,\n\t\t\t     10.0.0.2 }\n\t}\n"
      "\tchain input {\n\t\ttype filter hook input priority filter; policy drop;\n"
      "\t\tct state established,related accept\n\t\tiifname \"lo\" accept\n"
      "\t\tip daddr 224.0.0.0/4 udp dport 7667 accept comment \"LCM\"\n\t\ttcp dport 22 accept\n\t}\n}\n";
  const auto c = check_firewall(url, guarded, std::nullopt);
  EXPECT_EQ(c.level, CheckLevel::ok) << c.detail;
}

TEST(Firewall, ADropOfThePortFailsAndQuotesTheRule) {
  const auto url = url_of("udpm://239.255.76.67:7667?ttl=1");
  const std::string ruleset =
      "table inet filter {\n\tchain input {\n\t\ttype filter hook input priority filter; policy accept;\n"
      "\t\ttcp dport 22 accept\n\t\tudp dport { 5353, 7667 } counter packets 12 bytes 3400 drop # handle 7\n\t}\n}\n";
  const auto c = check_firewall(url, ruleset, std::nullopt);
  EXPECT_EQ(c.level, CheckLevel::fail);
  EXPECT_TRUE(contains(c.detail, "udp dport { 5353, 7667 }")) << c.detail;
  EXPECT_TRUE(contains(c.detail, "inet filter chain input")) << c.detail;
  EXPECT_TRUE(contains(c.fix, "nft insert rule inet filter input ip daddr 224.0.0.0/4 udp dport 7667 accept")) << c.fix;
}

TEST(Firewall, CatchAllRejectBeforeAnyAcceptFails) {
  const auto url = url_of("udpm://239.255.76.67:7667?ttl=1");
  const std::string ruleset =
      "table ip filter {\n\tchain INPUT {\n\t\ttype filter hook input priority filter; policy accept;\n"
      "\t\tct state invalid drop\n\t\tmeta l4proto udp reject with icmpx type admin-prohibited\n\t}\n}\n";
  EXPECT_EQ(check_firewall(url, ruleset, std::nullopt).level, CheckLevel::fail);
  // Dropping only invalid packets or other ports is fine.
  const std::string harmless =
      "table ip filter {\n\tchain INPUT {\n\t\ttype filter hook input priority filter; policy accept;\n"
      "\t\tct state invalid drop\n\t\tudp dport 53 drop\n\t}\n}\n";
  EXPECT_EQ(check_firewall(url, harmless, std::nullopt).level, CheckLevel::ok);
}

TEST(Firewall, PolicyDropWithoutAnAcceptWarns) {
  const auto url = url_of("udpm://239.255.76.67:7667?ttl=1");
  const std::string ruleset =
      "table inet filter {\n\tchain input {\n\t\ttype filter hook input priority filter; policy drop;\n"
      "\t\tct state established,related accept\n\t\ttcp dport 22 accept\n\t}\n}\n";
  const auto c = check_firewall(url, ruleset, std::nullopt);
  EXPECT_EQ(c.level, CheckLevel::warn);
  EXPECT_TRUE(contains(c.detail, "policy")) << c.detail;
}

TEST(Firewall, IptablesSave) {
  const auto url = url_of("udpm://239.255.76.67:7667?ttl=1");
  const std::string dropping =
      "# Generated by iptables-save\n*filter\n:INPUT ACCEPT [0:0]\n:FORWARD ACCEPT [0:0]\n:OUTPUT ACCEPT [0:0]\n"
      "-A INPUT -p udp -m udp --dport 7667 -j DROP\nCOMMIT\n";
  const auto c = check_firewall(url, std::nullopt, dropping);
  EXPECT_EQ(c.level, CheckLevel::fail);
  EXPECT_TRUE(contains(c.fix, "iptables -t filter -I INPUT -p udp -d 224.0.0.0/4 --dport 7667 -j ACCEPT")) << c.fix;
  const std::string ufw_like =
      "*filter\n:INPUT DROP [0:0]\n:OUTPUT ACCEPT [0:0]\n-A INPUT -i lo -j ACCEPT\n"
      "-A INPUT -m pkttype --pkt-type multicast -m comment --comment \"lab multicast\" -j ACCEPT\nCOMMIT\n";
  EXPECT_EQ(check_firewall(url, std::nullopt, ufw_like).level, CheckLevel::ok);
  const std::string closed = "*filter\n:INPUT DROP [0:0]\n-A INPUT -i lo -j ACCEPT\nCOMMIT\n";
  EXPECT_EQ(check_firewall(url, std::nullopt, closed).level, CheckLevel::warn);
  EXPECT_EQ(check_firewall(url, std::nullopt, std::nullopt).level, CheckLevel::skip);
}

// ---- serial ports, devices, bench files ---------------------------------------------------------

TEST(SerialInventory, FindsUsbSerialNumbersInASysfsTree) {
  TempDir d;
  // An Uno (ttyACM0: device = interface, parent = USB device with serial), an FTDI clone
  // (ttyUSB0: one level deeper, no serial), and a legacy ttyS0 without USB.
  const fs::path usb = d.path / "devices/pci0000:00/usb1";
  write(usb / "1-1.2/idVendor", "2341\n");
  write(usb / "1-1.2/idProduct", "0043\n");
  write(usb / "1-1.2/serial", "75833353035351B0F1A1\n");
  write(usb / "1-1.2/manufacturer", "Arduino (www.arduino.cc)\n");
  write(usb / "1-1.2/product", "Arduino Uno\n");
  fs::create_directories(usb / "1-1.2/1-1.2:1.0/tty/ttyACM0");
  write(usb / "1-1.3/idVendor", "1a86\n");
  write(usb / "1-1.3/idProduct", "7523\n");
  fs::create_directories(usb / "1-1.3/1-1.3:1.0/ttyUSB0/tty/ttyUSB0");
  fs::create_directories(d.path / "devices/platform/serial8250/tty/ttyS0");
  const fs::path cls = d.path / "class/tty";
  fs::create_directories(cls);
  fs::create_directory_symlink(usb / "1-1.2/1-1.2:1.0/tty/ttyACM0", cls / "ttyACM0");
  fs::create_directory_symlink(usb / "1-1.2/1-1.2:1.0", usb / "1-1.2/1-1.2:1.0/tty/ttyACM0/device");
  fs::create_directory_symlink(usb / "1-1.3/1-1.3:1.0/ttyUSB0/tty/ttyUSB0", cls / "ttyUSB0");
  fs::create_directory_symlink(usb / "1-1.3/1-1.3:1.0/ttyUSB0", usb / "1-1.3/1-1.3:1.0/ttyUSB0/tty/ttyUSB0/device");
  fs::create_directory_symlink(d.path / "devices/platform/serial8250/tty/ttyS0", cls / "ttyS0");
  fs::create_directory_symlink(d.path / "devices/platform/serial8250", d.path / "devices/platform/serial8250/tty/ttyS0/device");
  fs::create_directories(cls / "tty0");  // a console: no device link

  const auto ports = list_usb_serial_ports(cls);
  ASSERT_EQ(ports.size(), 2u);
  EXPECT_EQ(ports[0].device, "/dev/ttyACM0");
  EXPECT_EQ(ports[0].usb_serial, "75833353035351B0F1A1");
  EXPECT_EQ(ports[0].vendor_id, "2341");
  EXPECT_EQ(ports[0].product, "Arduino Uno");
  EXPECT_EQ(ports[0].usb_port, "1-1.2");
  EXPECT_EQ(udev_rule_line(ports[0], "bench-1"),
            "SUBSYSTEM==\"tty\", ATTRS{serial}==\"75833353035351B0F1A1\", ENV{SPINDOWN_BENCH}=\"bench-1\"");
  EXPECT_EQ(ports[1].device, "/dev/ttyUSB0");
  EXPECT_TRUE(ports[1].usb_serial.empty());
  EXPECT_TRUE(contains(udev_rule_line(ports[1], "bench-2"), "KERNELS==\"1-1.3\"")) << udev_rule_line(ports[1], "bench-2");
  EXPECT_TRUE(list_usb_serial_ports(d.path / "missing").empty());
}

namespace {
DeviceFacts serial_node(unsigned uid, unsigned gid, unsigned mode) {
  DeviceFacts f;
  f.exists = true;
  f.resolved = "/dev/ttyACM0";
  f.char_device = true;
  f.uid = uid;
  f.gid = gid;
  f.mode = mode;
  f.owner_name = "root";
  f.group_name = gid == 20 ? "dialout" : "plugdev";
  return f;
}
ServiceUser spindown_user(std::vector<unsigned> groups) {
  ServiceUser u;
  u.exists = true;
  u.uid = 998;
  u.gid = 998;
  u.groups = std::move(groups);
  u.dialout_gid = 20;
  return u;
}
}  // namespace

TEST(SerialDevice, DialoutGroupReadWriteIsOk) {
  const auto c = check_serial_device("bench-1", "/dev/spindown/bench-1", serial_node(0, 20, 0660), spindown_user({998, 20}), true);
  EXPECT_EQ(c.level, CheckLevel::ok) << c.detail;
  EXPECT_TRUE(contains(c.detail, "/dev/spindown/bench-1 -> /dev/ttyACM0 root:dialout 0660")) << c.detail;
  // The unit's SupplementaryGroups=dialout counts even when the user is not in dialout itself.
  EXPECT_EQ(check_serial_device("bench-1", "/dev/spindown/bench-1", serial_node(0, 20, 0660), spindown_user({998}), true).level,
            CheckLevel::ok);
}

TEST(SerialDevice, WrongGroupOrModeFails) {
  const auto c = check_serial_device("bench-1", "/dev/spindown/bench-1", serial_node(0, 46, 0660), spindown_user({998, 20}), true);
  EXPECT_EQ(c.level, CheckLevel::fail);
  EXPECT_TRUE(contains(c.detail, "not in group plugdev")) << c.detail;
  EXPECT_TRUE(contains(c.fix, "GROUP=\"dialout\", MODE=\"0660\"")) << c.fix;
  EXPECT_EQ(check_serial_device("bench-1", "/dev/spindown/bench-1", serial_node(0, 20, 0640), spindown_user({998, 20}), true).level,
            CheckLevel::fail);
}

TEST(SerialDevice, MissingDeviceFailsOnlyWhereTheBridgeRuns) {
  DeviceFacts missing;
  missing.error = "No such file or directory";
  const auto here = check_serial_device("bench-1", "/dev/spindown/bench-1", missing, spindown_user({20}), true);
  EXPECT_EQ(here.level, CheckLevel::fail);
  EXPECT_TRUE(contains(here.fix, "--serial-numbers")) << here.fix;
  EXPECT_EQ(check_serial_device("bench-1", "/dev/spindown/bench-1", missing, spindown_user({20}), false).level, CheckLevel::skip);
  EXPECT_EQ(check_serial_device("bench-1", "", missing, spindown_user({20}), true).level, CheckLevel::fail);
}

TEST(SerialDevice, UnstableNameWarnsAndMissingUserWarns) {
  const auto c = check_serial_device("bench-1", "/dev/ttyACM0", serial_node(0, 20, 0660), spindown_user({20}), true);
  EXPECT_EQ(c.level, CheckLevel::warn);
  EXPECT_TRUE(contains(c.fix, "/dev/spindown/bench-1")) << c.fix;
  ServiceUser nobody;
  EXPECT_EQ(check_serial_device("bench-1", "/dev/spindown/bench-1", serial_node(0, 20, 0660), nobody, true).level, CheckLevel::warn);
}

TEST(BenchFiles, ReadsADirectoryAndReportsMismatchesDuplicatesAndErrors) {
  TempDir d;
  write(d.path / "bench-1.toml", "bench_id = \"bench-1\"\n[serial]\ndevice = \"/dev/spindown/bench-1\"\n");
  write(d.path / "bench-2.toml", "bench_id = \"bench-7\"\n[serial]\ndevice = \"/dev/spindown/bench-1\"\n");
  write(d.path / "bench-3.toml", "[bench]\nquantity = \"furlongs\"\n");
  write(d.path / "notes.txt", "not a bench\n");
  const auto files = read_bench_files({d.path.string()});
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].stem, "bench-1");
  ASSERT_TRUE(files[0].settings);
  EXPECT_EQ(files[0].settings->device, "/dev/spindown/bench-1");
  EXPECT_FALSE(files[2].settings);
  EXPECT_TRUE(contains(files[2].error, "furlongs")) << files[2].error;

  const auto checks = check_bench_files(files, d.path.string());
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].level, CheckLevel::fail);
  EXPECT_TRUE(contains(checks[0].detail, "bench_id = \"bench-7\"")) << checks[0].detail;
  EXPECT_TRUE(contains(checks[0].detail, "benches bench-1, bench-2 all read /dev/spindown/bench-1")) << checks[0].detail;
  EXPECT_TRUE(contains(checks[0].detail, "furlongs")) << checks[0].detail;

  EXPECT_EQ(check_bench_files({files[0]}, "x")[0].level, CheckLevel::ok);
  EXPECT_EQ(check_bench_files({}, "x")[0].level, CheckLevel::warn);
}

// ---- clocks -------------------------------------------------------------------------------------

TEST(ClockSync, UnsynchronizedWarnsWithTheFix) {
  KernelClockState s;
  s.synchronized = false;
  const auto c = check_clock_sync(s, "");
  EXPECT_EQ(c.level, CheckLevel::warn);
  EXPECT_TRUE(contains(c.fix, "timedatectl set-ntp true")) << c.fix;
  s.synchronized = true;
  s.estimated_error_us = 1500;
  EXPECT_EQ(check_clock_sync(s, "chrony").level, CheckLevel::ok);
  EXPECT_EQ(check_clock_sync(std::nullopt, "").level, CheckLevel::skip);
  EXPECT_TRUE(read_kernel_clock_state().has_value());  // adjtimex read-only works unprivileged
}

TEST(ClockSkew, MedianPerHostAndLevels) {
  ClockSkewTracker t(100, 8);
  const std::int64_t now = 1'800'000'000'000'000;
  for (int i = 0; i < 50; ++i) {
    t.add("lab-pc-1", "bridge bench-1", now + i * 1000, now + i * 1000 + 300);        // 0.3 ms: network
    t.add("lab-pc-2", "bridge bench-2", now + i * 1000 - 2'000'000, now + i * 1000);  // its clock 2 s behind
  }
  t.add("lab-pc-3", "fitter fitter", now, now + 10'000'000);  // 10 s behind
  t.add("lab-pc-1", "logger logger", 0, now);                 // no utime: ignored
  const auto hosts = t.hosts();
  ASSERT_EQ(hosts.size(), 3u);
  EXPECT_EQ(hosts[0].host, "lab-pc-1");
  EXPECT_EQ(hosts[0].messages, 50u);
  EXPECT_NEAR(hosts[0].median_s, 0.0003, 1e-9);
  EXPECT_EQ(hosts[0].senders.size(), 1u);
  EXPECT_NEAR(hosts[1].median_s, 2.0, 1e-9);
  const auto checks = check_clock_skew(hosts, "lab-pc-1", 3);
  ASSERT_EQ(checks.size(), 3u);
  EXPECT_EQ(checks[0].level, CheckLevel::ok);
  EXPECT_TRUE(contains(checks[0].detail, "this PC")) << checks[0].detail;
  EXPECT_EQ(checks[1].level, CheckLevel::warn);
  EXPECT_TRUE(contains(checks[1].detail, "2 s behind")) << checks[1].detail;
  EXPECT_EQ(checks[2].level, CheckLevel::fail);
  EXPECT_EQ(check_clock_skew({}, "x", 3)[0].level, CheckLevel::skip);
}

TEST(ClockSkew, BoundedInHostsAndSamples) {
  ClockSkewTracker t(10, 2);
  for (int i = 0; i < 100; ++i) t.add("h" + std::to_string(i % 5), "s", 1000 + i, 2000 + i);
  const auto hosts = t.hosts();
  ASSERT_EQ(hosts.size(), 2u);
  EXPECT_EQ(hosts[0].messages, 20u);  // counted, though only 10 kept for the median
}

// ---- the report ---------------------------------------------------------------------------------

TEST(DoctorReport, TextJsonAndExitCode) {
  std::vector<DoctorCheck> checks = {{"multicast route", CheckLevel::ok, "239.255.76.67 goes out on lo", ""},
                                     {"firewall", CheckLevel::skip, "cannot read", ""}};
  EXPECT_EQ(doctor_exit_code(checks), 0);
  checks.push_back({"LCM TTL", CheckLevel::warn, "ttl=0", "set ttl=1\nand reload"});
  EXPECT_EQ(doctor_exit_code(checks), 1);
  checks.push_back({"LCM self-test", CheckLevel::fail, "nothing came back", "ip route add 224.0.0.0/4 dev lo"});
  EXPECT_EQ(doctor_exit_code(checks), 2);
  const std::string text = render_doctor_text(checks);
  EXPECT_TRUE(contains(text, "ok    multicast route  239.255.76.67 goes out on lo\n")) << text;
  EXPECT_TRUE(contains(text, "fail  LCM self-test    nothing came back\n      fix: ip route add 224.0.0.0/4 dev lo\n")) << text;
  EXPECT_TRUE(contains(text, "      fix: set ttl=1\n           and reload\n")) << text;
  EXPECT_TRUE(contains(text, "doctor: 1 ok, 1 warning, 1 failure, 1 skipped")) << text;
  const auto j = doctor_json(checks);
  EXPECT_EQ(j["exit_code"], 2);
  EXPECT_EQ(j["checks"][3]["level"], "fail");
  EXPECT_EQ(j["summary"]["warn"], 1);
}

// ---- LCM self-test (memq: inside this process, no network) ----------------------------------------

TEST(LcmSelfTest, MemqRoundTrip) {
  const auto t = run_lcm_self_test("memq://", 2.0);
  EXPECT_TRUE(t.started);
  EXPECT_TRUE(t.received);
  EXPECT_GE(t.published, 1);
  EXPECT_TRUE(t.channel.rfind("SPINDOWN_DOCTOR.", 0) == 0) << t.channel;
  EXPECT_EQ(check_lcm_self_test(t).level, CheckLevel::ok);
  LcmSelfTest failed;
  failed.url = "udpm://239.255.76.67:7667";
  EXPECT_EQ(check_lcm_self_test(failed).level, CheckLevel::fail);
  failed.started = true;  // LCM 1.3.1's own receive setup failed (firewall)
  EXPECT_TRUE(contains(check_lcm_self_test(failed).detail, "cannot receive"));
  failed.receiving = true;
  failed.published = 10;
  EXPECT_TRUE(contains(check_lcm_self_test(failed).detail, "none came back"));
  EXPECT_EQ(check_lcm_self_test(failed).level, CheckLevel::fail);
  const auto bad = run_lcm_self_test("nosuchprovider://", 0.2);
  EXPECT_FALSE(bad.started);
}
