#pragma once
// What `spindown doctor` asks of this machine, without judging it (network_checks.hpp and
// clock_checks.hpp judge): files under /proc and /sys, programs in PATH and their output, the
// network interfaces of this namespace, the NTP client running, and the lab's clocks heard on
// LCM. Each answers "unknown" (nullopt, empty) rather than throwing.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "spindown/clock_checks.hpp"
#include "spindown/lab_key.hpp"
#include "spindown/lab_traffic.hpp"
#include "spindown/network_checks.hpp"

namespace spindown {

// A whole file's text; nullopt when it cannot be read.
std::optional<std::string> read_file(const std::filesystem::path& path);
// A file holding one integer (sysctl values); nullopt when unreadable or not a number.
std::optional<long> read_long(const std::filesystem::path& path);
// A program in PATH or the admin directories (nft and iptables live in /usr/sbin); "" if none.
std::string find_program(const std::string& name);
// Runs a program (no shell), its stdout captured (at most 4 MB); nullopt when it cannot run or
// exits non-zero (then *why holds its first stderr line or the exit status).
std::optional<std::string> capture(const std::vector<std::string>& argv, std::string* why);
// The interfaces of this network namespace (getifaddrs), sorted by name.
std::vector<NetInterface> read_interfaces();
// The NTP client running here ("chrony", "systemd-timesyncd", "ntpd", "openntpd"), "" if none.
std::string running_ntp_client();
// Listens on url for `seconds` to every SPINDOWN.* message: each host's clock skew against this
// one (from STATUS and CONFIG), and who sends (lab_traffic.hpp; signatures checked with key
// when given). listened is false when LCM cannot listen.
struct LabListen {
  bool listened = false;
  std::vector<HostSkew> clocks;
  LabTraffic traffic;
};
LabListen listen_to_lab(const std::string& url, double seconds, const LabKey* key = nullptr);

}  // namespace spindown
