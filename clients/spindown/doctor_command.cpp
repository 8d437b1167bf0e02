#include "doctor_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>
#include <memory>
#include <unistd.h>

#include "exit_codes.hpp"
#include "spindown/clock.hpp"
#include "spindown/clock_checks.hpp"
#include "spindown/doctor_check.hpp"
#include "spindown/host_name.hpp"
#include "spindown/lcm_self_test.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/network_checks.hpp"
#include "spindown/serial_inventory.hpp"
#include "spindown/system_probes.hpp"

namespace spindown::cli {

namespace fs = std::filesystem;

namespace {

const std::vector<std::string> all_checks = {"ttl", "route", "firewall", "buffer", "selftest", "serial", "clock", "lab"};

bool wanted(const DoctorCommandOptions& o, const std::string& check) {
  return o.checks.empty() || std::find(o.checks.begin(), o.checks.end(), check) != o.checks.end();
}

int list_serial_numbers(const DoctorCommandOptions& o) {
  const auto ports = list_usb_serial_ports(o.sysfs_tty);
  if (o.json) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& p : ports)
      list.push_back({{"device", p.device}, {"serial", p.usb_serial}, {"vendor_id", p.vendor_id}, {"product_id", p.product_id},
                      {"manufacturer", p.manufacturer}, {"product", p.product}, {"usb_port", p.usb_port},
                      {"udev_rule", udev_rule_line(p, "BENCH")}});
    std::cout << nlohmann::json{{"ports", list}}.dump(2) << '\n';
    return ports.empty() ? exit_unusable : exit_ok;
  }
  if (ports.empty()) {
    std::cout << "no USB serial port found under " << o.sysfs_tty
              << ": is the Arduino plugged in (and powered)? `dmesg | tail` shows what the kernel saw\n";
    return exit_unusable;
  }
  for (const auto& p : ports) {
    std::cout << fmt::format("{}  serial {}  USB {}:{} {}{}{}  port {}\n", p.device,
                             p.usb_serial.empty() ? "(none)" : p.usb_serial, p.vendor_id, p.product_id, p.manufacturer,
                             p.manufacturer.empty() || p.product.empty() ? "" : " ", p.product, p.usb_port);
    std::cout << "  " << udev_rule_line(p, "BENCH") << '\n';
  }
  std::cout << "Put each line in /etc/udev/rules.d/99-spindown.rules with BENCH = the bench id, then\n"
               "  udevadm control --reload && udevadm trigger --subsystem-match=tty\n";
  return exit_ok;
}

}  // namespace

void setup_doctor(CLI::App& app) {
  auto opt = std::make_shared<DoctorCommandOptions>();
  CLI::App* sub = app.add_subcommand("doctor", "Check what breaks LCM labs on this PC and say how to fix each");
  sub->footer(
      "Checks: ttl (LCM URL's TTL: 0 this host, 1 the lab LAN), route (a route for the multicast group), firewall "
      "(nft/iptables rules dropping UDP to the LCM port or multicast; read-only, needs root to read them), buffer "
      "(net.core.rmem_max vs LCM's recommended 2 MB), selftest (an LCM message published and received on the URL), "
      "serial (bench files; each bench's device exists and the service user may read and write it), clock (this PC's "
      "NTP sync; the clock skew of every lab PC heard on LCM during --listen), lab (who sends on the group and port during "
      "--listen: another lab's traffic, senders that name no lab, unsigned messages with --key, a bench with two "
      "sources, two services with one name).\n"
      "The LCM URL: --lcm-url, else LCM_DEFAULT_URL, else the one in /etc/spindown/lcm.env (the services'), else "
      "LCM's default.\n"
      "Exit codes: 0 every check ok (or skipped), 1 warnings, 2 failures or bad usage. --serial-numbers: 0 ports "
      "found, 1 none.");
  sub->add_option("--lcm-url", opt->lcm_url, "LCM URL to check (default: LCM_DEFAULT_URL, else /etc/spindown/lcm.env)");
  sub->add_option("--env-file", opt->env_file, "The services' LCM env file")->capture_default_str();
  sub->add_option("--bench-config", opt->bench_config,
                  "Bench files or directories (default /etc/spindown/benches when it exists); repeat the flag for more")
      ->allow_extra_args(false);
  sub->add_option("--service-user", opt->service_user, "User the services run as")->capture_default_str();
  sub->add_option("--checks", opt->checks, "Only these checks: ttl,route,firewall,buffer,selftest,serial,clock,lab")
      ->delimiter(',')
      ->allow_extra_args(false)
      ->check(CLI::IsMember(all_checks));
  sub->add_option("--timeout", opt->timeout_s, "Seconds the LCM self-test waits for its message")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 30.0));
  add_lab_options(sub, opt->lab, "");
  sub->add_option("--listen", opt->listen_s,
                  "Seconds to listen for the lab's traffic: other PCs' clocks, other labs, sources (0: do not listen)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 60.0));
  sub->add_flag("--single-host", opt->single_host, "The whole lab runs on this PC: ttl=0 is intended");
  sub->add_flag("--json", opt->json, "One JSON object: checks with name, level, detail, fix; summary; exit_code");
  sub->add_flag("--serial-numbers", opt->serial_numbers,
                "List USB serial ports with their boards' serial numbers and the udev rule line for each");
  sub->add_option("--sysfs-tty", opt->sysfs_tty, "Where the tty class lives (tests give a fixture)")->capture_default_str();
  sub->callback([opt]() {
    const int code = run_doctor(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_doctor(const DoctorCommandOptions& o) {
  if (o.serial_numbers) return list_serial_numbers(o);
  std::vector<DoctorCheck> checks;

  // The URL: what this process would use, and what the services use.
  std::optional<std::string> services_url;
  LabOptions lab_options = o.lab;  // the services' lab when neither --lab nor $SPINDOWN_LAB names one
  if (const auto text = read_file(o.env_file)) {
    const auto env = parse_env_file(*text);
    if (const auto it = env.find("LCM_DEFAULT_URL"); it != env.end() && !it->second.empty()) services_url = it->second;
    const char* lab_env = std::getenv("SPINDOWN_LAB");
    if (const auto it = env.find("SPINDOWN_LAB");
        it != env.end() && !it->second.empty() && lab_options.lab.empty() && !(lab_env && *lab_env))
      lab_options.lab = it->second;
  }
  const char* env = std::getenv("LCM_DEFAULT_URL");
  const auto resolved = resolve_lcm_url(o.lcm_url, env && *env ? std::optional<std::string>(env) : std::nullopt,
                                        services_url, o.env_file);
  std::string why;
  const auto url = parse_lcm_url(resolved.url, &why);
  const bool network = wanted(o, "ttl") || wanted(o, "route") || wanted(o, "firewall") || wanted(o, "buffer") ||
                       wanted(o, "selftest");
  if (!url && network) {
    checks.push_back({"LCM URL", CheckLevel::fail, fmt::format("{} (from {})", why, resolved.source),
                      "LCM_DEFAULT_URL=udpm://239.255.76.67:7667?ttl=1 in /etc/spindown/lcm.env"});
  }
  bool lcm_works = false;
  if (url) {
    if (wanted(o, "ttl")) checks.push_back(check_lcm_ttl(*url, resolved.source, o.single_host, services_url));
    if (wanted(o, "route")) {
      const auto routes = parse_proc_net_route(read_file("/proc/net/route").value_or(""));
      checks.push_back(check_multicast_route(*url, routes, read_interfaces()));
    }
    if (wanted(o, "firewall")) {
      std::optional<std::string> nft, ipt;
      std::string nft_why, ipt_why;
      const std::string nft_bin = find_program("nft");
      const std::string ipt_bin = find_program("iptables-save");
      if (!nft_bin.empty()) nft = capture({nft_bin, "list", "ruleset"}, &nft_why);
      // iptables-nft rules are in nft's ruleset already; iptables-save only without nft.
      if (!nft && !ipt_bin.empty()) ipt = capture({ipt_bin}, &ipt_why);
      if (!nft && !ipt && (!nft_bin.empty() || !ipt_bin.empty())) {
        checks.push_back({"firewall", CheckLevel::skip,
                          fmt::format("cannot read the rules ({}{}): run spindown doctor as root to check them",
                                      nft_bin.empty() ? "iptables-save: " + ipt_why : "nft list ruleset: " + nft_why,
                                      ""),
                          ""});
      } else {
        checks.push_back(check_firewall(*url, nft, ipt));
      }
    }
    if (wanted(o, "buffer")) {
      std::optional<long> errors;
      if (const auto snmp = read_file("/proc/net/snmp")) errors = parse_udp_rcvbuf_errors(*snmp);
      checks.push_back(check_receive_buffer(read_long("/proc/sys/net/core/rmem_max"), errors));
    }
    if (wanted(o, "selftest")) {
      const auto t = run_lcm_self_test(resolved.url, o.timeout_s);
      lcm_works = t.received;
      checks.push_back(check_lcm_self_test(t));
    } else {
      lcm_works = true;  // not tested: try to listen anyway
    }
  }

  if (wanted(o, "serial")) {
    std::vector<std::string> sources = o.bench_config;
    std::error_code ec;
    if (sources.empty() && fs::is_directory("/etc/spindown/benches", ec)) sources.push_back("/etc/spindown/benches");
    if (sources.empty()) {
      checks.push_back({"bench files", CheckLevel::skip, "no /etc/spindown/benches on this PC (no bench configured here)", ""});
    } else {
      std::string where;
      for (const auto& s : sources) where += (where.empty() ? "" : ", ") + s;
      const auto files = read_bench_files(sources);
      for (auto& c : check_bench_files(files, where)) checks.push_back(std::move(c));
      const ServiceUser user = lookup_service_user(o.service_user);
      for (const auto& f : files) {
        if (!f.settings) continue;
        const bool enabled_here =
            fs::exists(fmt::format("/etc/systemd/system/multi-user.target.wants/spindown-bridge@{}.service", f.stem), ec);
        checks.push_back(check_serial_device(f.stem, f.settings->device, device_facts(f.settings->device), user, enabled_here));
      }
    }
  }

  // One listen for the clocks and the lab's traffic.
  const LabSettings lab = lab_settings_from(lab_options);
  std::optional<LabListen> heard;
  if ((wanted(o, "clock") || wanted(o, "lab")) && o.listen_s > 0 && url && lcm_works) {
    if (!o.json)
      std::fprintf(stderr, "spindown doctor: listening %.3g s to the lab on %s\n", o.listen_s, resolved.url.c_str());
    heard = listen_to_lab(resolved.url, o.listen_s, lab.key ? &*lab.key : nullptr);
  }
  if (wanted(o, "clock")) {
    checks.push_back(check_clock_sync(read_kernel_clock_state(), running_ntp_client()));
    if (heard && heard->listened) {
      for (auto& c : check_clock_skew(heard->clocks, host_name(), o.listen_s)) checks.push_back(std::move(c));
    } else if (o.listen_s > 0) {
      checks.push_back({"clock skew", CheckLevel::skip, "LCM does not work here: no other PC's clock to compare", ""});
    }
  }
  if (wanted(o, "lab")) {
    if (heard && heard->listened) {
      for (auto& c : heard->traffic.checks(lab.lab, lab.key, resolved.url, o.listen_s, wall_us()))
        checks.push_back(std::move(c));
    } else {
      checks.push_back({"lab traffic", CheckLevel::skip,
                        o.listen_s > 0 ? "LCM does not work here: cannot listen to the lab"
                                       : "not listened (--listen 0)",
                        ""});
    }
  }

  if (o.json) {
    auto j = doctor_json(checks);
    j["lcm_url"] = resolved.url;
    j["lcm_url_source"] = resolved.source;
    std::cout << j.dump(2) << '\n';
  } else {
    std::cout << render_doctor_text(checks);
  }
  std::cout.flush();
  return doctor_exit_code(checks);
}

}  // namespace spindown::cli
