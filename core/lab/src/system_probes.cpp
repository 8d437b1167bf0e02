#include "spindown/system_probes.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fmt/format.h>
#include <fstream>
#include <ifaddrs.h>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

#include <spindown/config_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/quiet_stderr.hpp"

namespace spindown {

namespace fs = std::filesystem;

std::optional<std::string> read_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) return std::nullopt;
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::optional<long> read_long(const fs::path& path) {
  const auto text = read_file(path);
  if (!text) return std::nullopt;
  try {
    return std::stol(*text);
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

// A program in PATH or the admin directories (nft and iptables live in /usr/sbin).
std::string find_program(const std::string& name) {
  std::string path = std::getenv("PATH") ? std::getenv("PATH") : "";
  path += ":/usr/sbin:/sbin";
  std::istringstream dirs(path);
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const fs::path p = fs::path(dir) / name;
    if (::access(p.c_str(), X_OK) == 0) return p.string();
  }
  return {};
}

// Runs a program (no shell), its stdout captured (at most 4 MB); nullopt when it cannot run or
// exits non-zero (then why holds its first stderr line or the exit status).
std::optional<std::string> capture(const std::vector<std::string>& argv, std::string* why) {
  int out_pipe[2], err_pipe[2];
  if (::pipe(out_pipe) != 0) return std::nullopt;
  if (::pipe(err_pipe) != 0) {
    ::close(out_pipe[0]);
    ::close(out_pipe[1]);
    return std::nullopt;
  }
  const pid_t pid = ::fork();
  if (pid < 0) return std::nullopt;
  if (pid == 0) {
    ::dup2(out_pipe[1], 1);
    ::dup2(err_pipe[1], 2);
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    _exit(127);
  }
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  std::string out, err;
  char buf[4096];
  for (ssize_t n; (n = ::read(out_pipe[0], buf, sizeof buf)) > 0;)
    if (out.size() < (4u << 20)) out.append(buf, static_cast<std::size_t>(n));
  for (ssize_t n; (n = ::read(err_pipe[0], buf, sizeof buf)) > 0;)
    if (err.size() < 4096) err.append(buf, static_cast<std::size_t>(n));
  ::close(out_pipe[0]);
  ::close(err_pipe[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return out;
  if (why) {
    *why = err.substr(0, err.find('\n'));
    if (why->empty()) *why = fmt::format("exit status {}", WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  }
  return std::nullopt;
}

// The interfaces of this network namespace (getifaddrs asks the kernel; /sys/class/net would
// show the namespace sysfs was mounted in).
std::vector<NetInterface> read_interfaces() {
  std::vector<NetInterface> out;
  ifaddrs* list = nullptr;
  if (::getifaddrs(&list) != 0) return out;
  for (const ifaddrs* a = list; a; a = a->ifa_next) {
    if (!a->ifa_name) continue;
    if (std::any_of(out.begin(), out.end(), [&](const NetInterface& i) { return i.name == a->ifa_name; })) continue;
    if (auto i = interface_from_flags(a->ifa_name, fmt::format("{:x}", a->ifa_flags))) out.push_back(*i);
  }
  ::freeifaddrs(list);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return out;
}

// The NTP client running here, from the process names.
std::string running_ntp_client() {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator("/proc", ec)) {
    const std::string pid = e.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    auto comm = read_file(e.path() / "comm");
    if (!comm) continue;
    while (!comm->empty() && comm->back() == '\n') comm->pop_back();
    if (*comm == "chronyd") return "chrony";
    if (*comm == "systemd-timesyn") return "systemd-timesyncd";
    if (*comm == "ntpd") return "ntpd";
    if (*comm == "openntpd") return "openntpd";
  }
  return {};
}

LabListen listen_to_lab(const std::string& url, double seconds, const LabKey* key) {
  LabListen out;
  ClockSkewTracker tracker;
  // LCM 1.3.1 prints its own multicast advice on stderr; the self-test above has reported it.
  QuietStderr quiet;
  LcmLoop loop(url);
  if (!loop.good()) return out;
  const bool subscribed = loop.subscribe_raw(
      "SPINDOWN\\..*",
      [&](const LcmMessage& r) {
        const std::int64_t received = r.recv_utime > 0 ? r.recv_utime : wall_us();
        const auto parsed = parse_channel(r.channel);
        if (!parsed) return;
        status_t status{};
        const bool is_status = parsed->kind == ChannelKind::status && decode_message(status, r.data, r.size);
        if (is_status) tracker.add(status.host, status.service + " " + status.instance, status.utime, received);
        if (parsed->kind == ChannelKind::config) {
          config_t config{};
          if (decode_message(config, r.data, r.size))
            tracker.add(config.host, "bridge " + config.bench, config.utime, received);
        }
        out.traffic.add(r.channel, r.data, r.size, received, is_status ? &status : nullptr, key);
      },
      {.queue_capacity = 10000});
  // LCM 1.3.1: no receive socket after its own loopback self-test failed.
  if (!subscribed || !loop.can_receive()) return out;
  quiet.restore();
  loop.run({.timeout_s = seconds, .max_wait_ms = 50, .max_failures = 0});
  out.listened = true;
  out.clocks = tracker.hosts();
  return out;
}

}  // namespace spindown
