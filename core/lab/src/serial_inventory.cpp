#include "spindown/serial_inventory.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fmt/format.h>
#include <fstream>
#include <grp.h>
#include <map>
#include <pwd.h>
#include <sys/stat.h>
#include <system_error>

namespace spindown {

namespace fs = std::filesystem;

namespace {

std::string read_attribute(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  if (!in || !std::getline(in, line)) return {};
  while (!line.empty() && (line.back() == '\n' || line.back() == '\r' || line.back() == ' ')) line.pop_back();
  return line;
}

std::string octal_mode(unsigned mode) { return fmt::format("{:04o}", mode & 07777); }

std::string rw_text(unsigned bits) {
  std::string s;
  s += (bits & 4) ? 'r' : '-';
  s += (bits & 2) ? 'w' : '-';
  return s;
}

}  // namespace

std::vector<SerialPortInfo> list_usb_serial_ports(const fs::path& sysfs_class_tty) {
  std::vector<SerialPortInfo> ports;
  std::error_code ec;
  fs::directory_iterator it(sysfs_class_tty, ec);
  if (ec) return ports;
  for (const auto& entry : it) {
    const fs::path device_link = entry.path() / "device";
    if (!fs::exists(device_link, ec)) continue;  // virtual terminals, pty masters
    fs::path dir = fs::canonical(device_link, ec);
    if (ec) continue;
    // ttyACM: device = the USB interface, its parent the USB device; ttyUSB: one level more.
    bool found = false;
    for (int up = 0; up < 5 && !dir.empty() && dir != dir.root_path(); ++up) {
      if (fs::exists(dir / "idVendor", ec)) {
        found = true;
        break;
      }
      dir = dir.parent_path();
    }
    if (!found) continue;
    SerialPortInfo p;
    p.name = entry.path().filename().string();
    p.device = "/dev/" + p.name;
    p.usb_serial = read_attribute(dir / "serial");
    p.vendor_id = read_attribute(dir / "idVendor");
    p.product_id = read_attribute(dir / "idProduct");
    p.manufacturer = read_attribute(dir / "manufacturer");
    p.product = read_attribute(dir / "product");
    p.usb_port = dir.filename().string();
    ports.push_back(std::move(p));
  }
  std::sort(ports.begin(), ports.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  return ports;
}

std::string udev_rule_line(const SerialPortInfo& port, const std::string& bench) {
  if (!port.usb_serial.empty())
    return fmt::format("SUBSYSTEM==\"tty\", ATTRS{{serial}}==\"{}\", ENV{{SPINDOWN_BENCH}}=\"{}\"", port.usb_serial, bench);
  return fmt::format("SUBSYSTEM==\"tty\", KERNELS==\"{}\", ENV{{SPINDOWN_BENCH}}=\"{}\"   # no serial number: by USB port",
                     port.usb_port, bench);
}

DeviceFacts device_facts(const std::string& path) {
  DeviceFacts f;
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    f.error = std::strerror(errno);
    return f;
  }
  f.exists = true;
  std::error_code ec;
  const fs::path resolved = fs::canonical(path, ec);
  f.resolved = ec ? path : resolved.string();
  f.char_device = S_ISCHR(st.st_mode);
  f.mode = st.st_mode & 07777;
  f.uid = st.st_uid;
  f.gid = st.st_gid;
  if (const passwd* pw = ::getpwuid(st.st_uid)) f.owner_name = pw->pw_name;
  else f.owner_name = std::to_string(st.st_uid);
  if (const group* gr = ::getgrgid(st.st_gid)) f.group_name = gr->gr_name;
  else f.group_name = std::to_string(st.st_gid);
  return f;
}

ServiceUser lookup_service_user(const std::string& name) {
  ServiceUser u;
  u.name = name;
  if (const group* gr = ::getgrnam("dialout")) u.dialout_gid = gr->gr_gid;
  const passwd* pw = ::getpwnam(name.c_str());
  if (!pw) return u;
  u.exists = true;
  u.uid = pw->pw_uid;
  u.gid = pw->pw_gid;
  int n = 64;
  std::vector<gid_t> groups(static_cast<std::size_t>(n));
  if (::getgrouplist(name.c_str(), pw->pw_gid, groups.data(), &n) < 0) {
    groups.resize(static_cast<std::size_t>(n));
    ::getgrouplist(name.c_str(), pw->pw_gid, groups.data(), &n);
  }
  groups.resize(static_cast<std::size_t>(std::max(n, 0)));
  for (gid_t g : groups) u.groups.push_back(g);
  return u;
}

DoctorCheck check_serial_device(const std::string& bench, const std::string& device, const DeviceFacts& f,
                                const ServiceUser& user, bool bridge_enabled_here) {
  DoctorCheck c{"serial " + bench, CheckLevel::ok, "", ""};
  const std::string udev_name = "/dev/spindown/" + bench;
  const std::string file = fmt::format("/etc/spindown/benches/{}.toml", bench);
  if (device.empty()) {
    c.level = CheckLevel::fail;
    c.detail = "no [serial] device in the bench file";
    c.fix = fmt::format("[serial] device = \"{}\" in {}", udev_name, file);
    return c;
  }
  if (!f.exists) {
    if (!bridge_enabled_here) {
      c.level = CheckLevel::skip;
      c.detail = fmt::format("{}: {} (its bridge is not enabled on this PC)", device, f.error);
      return c;
    }
    c.level = CheckLevel::fail;
    c.detail = fmt::format("{}: {}: the Arduino is unplugged, or the udev rule does not know its serial number", device,
                           f.error);
    c.fix = "spindown doctor --serial-numbers   # the plugged-in boards and the rule line for each\n"
            "edit /etc/udev/rules.d/99-spindown.rules, then: udevadm control --reload && udevadm trigger --subsystem-match=tty";
    return c;
  }
  const std::string node = f.resolved != device ? fmt::format("{} -> {}", device, f.resolved) : device;
  if (!f.char_device) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("{} is not a character device (not a serial port)", node);
    c.fix = fmt::format("[serial] device = \"{}\" in {}", udev_name, file);
    return c;
  }
  const std::string perms = fmt::format("{} {}:{} {}", node, f.owner_name, f.group_name, octal_mode(f.mode));
  if (!user.exists) {
    c.level = CheckLevel::warn;
    c.detail = fmt::format("{}; no user '{}' on this PC to check it for", perms, user.name);
    c.fix = "deploy/install-lab   # creates the service user (systemd-sysusers)";
    return c;
  }
  // The permission the kernel applies: owner, else group (the user's groups plus dialout from
  // the unit's SupplementaryGroups=), else others.
  const bool in_group = f.gid == user.gid || std::find(user.groups.begin(), user.groups.end(), f.gid) != user.groups.end() ||
                        (user.dialout_gid && f.gid == *user.dialout_gid);
  const unsigned bits = f.uid == user.uid ? (f.mode >> 6) & 7 : in_group ? (f.mode >> 3) & 7 : f.mode & 7;
  if ((bits & 6) != 6) {
    c.level = CheckLevel::fail;
    c.detail = fmt::format("{}: user {} may only '{}' it (needs rw){}", perms, user.name, rw_text(bits),
                           in_group ? "" : fmt::format(" and is not in group {}", f.group_name));
    c.fix = "GROUP=\"dialout\", MODE=\"0660\" in /etc/udev/rules.d/99-spindown.rules (the shipped rule has them), then\n"
            "udevadm control --reload && udevadm trigger --subsystem-match=tty";
    return c;
  }
  c.detail = fmt::format("{}: user {} may read and write it", perms, user.name);
  if (device != udev_name) {
    c.level = CheckLevel::warn;
    c.detail += fmt::format("; but the bridge unit only allows {} (DeviceAllow=), and ttyACM numbers change with the plug order",
                            udev_name);
    c.fix = fmt::format("[serial] device = \"{}\" in {} (and the bench's line in 99-spindown.rules)", udev_name, file);
  }
  return c;
}

std::vector<BridgeBenchFile> read_bench_files(const std::vector<std::string>& files_or_dirs) {
  std::vector<std::string> paths;
  for (const auto& p : files_or_dirs) {
    std::error_code ec;
    if (fs::is_directory(p, ec)) {
      std::vector<std::string> in_dir;
      for (const auto& e : fs::directory_iterator(p, ec))
        if (e.path().extension() == ".toml") in_dir.push_back(e.path().string());
      std::sort(in_dir.begin(), in_dir.end());
      paths.insert(paths.end(), in_dir.begin(), in_dir.end());
    } else {
      paths.push_back(p);
    }
  }
  std::vector<BridgeBenchFile> out;
  for (const auto& path : paths) {
    BridgeBenchFile b;
    b.path = path;
    b.stem = fs::path(path).stem().string();
    try {
      BridgeSettings s;
      load_bridge_settings(path, s);
      b.settings = s;
    } catch (const std::exception& e) {
      b.error = e.what();
    }
    out.push_back(std::move(b));
  }
  return out;
}

std::vector<DoctorCheck> check_bench_files(const std::vector<BridgeBenchFile>& files, const std::string& where) {
  std::vector<DoctorCheck> out;
  if (files.empty()) {
    out.push_back({"bench files", CheckLevel::warn, fmt::format("no bench file in {}", where),
                   "cp /usr/local/share/doc/spindown/example.toml /etc/spindown/benches/BENCH.toml   # one per bench, then edit it"});
    return out;
  }
  std::map<std::string, std::vector<std::string>> by_device;
  std::vector<std::string> problems, fixes, names;
  CheckLevel level = CheckLevel::ok;
  for (const auto& f : files) {
    names.push_back(f.stem);
    if (!f.settings) {
      level = CheckLevel::fail;
      problems.push_back(f.error);
      fixes.push_back(fmt::format("edit {}", f.path));
      continue;
    }
    if (!f.settings->bench.empty() && f.settings->bench != f.stem) {
      level = std::max(level, CheckLevel::warn);
      problems.push_back(fmt::format("{} says bench_id = \"{}\", but its bridge unit spindown-bridge@{} publishes as '{}'",
                                     f.path, f.settings->bench, f.stem, f.stem));
      fixes.push_back(fmt::format("bench_id = \"{}\" in {} (or rename the file to {}.toml)", f.stem, f.path, f.settings->bench));
    }
    if (!f.settings->device.empty()) by_device[f.settings->device].push_back(f.stem);
  }
  for (const auto& [device, benches] : by_device) {
    if (benches.size() < 2) continue;
    level = CheckLevel::fail;
    std::string list;
    for (const auto& b : benches) list += (list.empty() ? "" : ", ") + b;
    problems.push_back(fmt::format("benches {} all read {}", list, device));
    fixes.push_back("[serial] device = \"/dev/spindown/BENCH\" in each bench's file");
  }
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : " ") + n;
  DoctorCheck c{"bench files", level, fmt::format("{} bench{} in {}: {}", files.size(), files.size() == 1 ? "" : "es", where, list), ""};
  for (const auto& p : problems) c.detail += "; " + p;
  for (const auto& fx : fixes) c.fix += (c.fix.empty() ? "" : "\n") + fx;
  out.push_back(c);
  return out;
}

}  // namespace spindown
