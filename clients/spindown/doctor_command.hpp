#pragma once
// `spindown doctor`: checks what breaks LCM labs on this PC and says how to fix each — the LCM
// URL's TTL, the multicast route, the firewall, the socket receive buffer, an LCM round trip,
// the bench files and each bench's serial device (exists, read/write for the service user),
// this PC's clock sync and the clock skew of every lab PC heard on LCM. One line per check
// (ok / warn / fail / skip) and the fix command under each problem; --json for scripts.
// `spindown doctor --serial-numbers` lists the USB serial ports and their boards' serial numbers
// with the udev rule line for each. The checks themselves live in the core library
// (network_checks, lcm_self_test, serial_inventory, clock_checks).
#include <string>
#include <vector>

#include "lab_options.hpp"

namespace CLI {
class App;
}

namespace spindown::cli {

struct DoctorCommandOptions {
  std::string lcm_url;                     // "" = LCM_DEFAULT_URL, else env_file's, else LCM's default
  std::string env_file = "/etc/spindown/lcm.env";
  std::vector<std::string> bench_config;   // bench files or directories (default /etc/spindown/benches)
  std::string service_user = "spindown";
  std::vector<std::string> checks;         // subset of: ttl route firewall buffer selftest serial clock
  double timeout_s = 2.0;                  // LCM self-test
  LabOptions lab;                          // this PC's lab and key (--lab, --key)
  double listen_s = 3.0;                   // listening for other hosts' clocks; 0 = no listening
  bool single_host = false;                // ttl=0 is intended (the whole lab on this PC)
  bool json = false;
  bool serial_numbers = false;             // only list the USB serial ports
  std::string sysfs_tty = "/sys/class/tty";
};

void setup_doctor(CLI::App& app);
// Exit code: 0 every check ok, 1 warnings, 2 failures (bad usage is also 2).
// --serial-numbers: 0 when a USB serial port was found, 1 when none.
int run_doctor(const DoctorCommandOptions& options);

}  // namespace spindown::cli
