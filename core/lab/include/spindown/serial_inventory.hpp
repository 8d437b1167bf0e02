#pragma once
// The serial side of a lab PC for `spindown doctor`: which USB serial ports exist and the USB
// serial number of the board behind each (for the udev rule that names each bench's Arduino
// /dev/spindown/<bench>), whether each configured bench's device exists and the service user
// may read and write it, and whether the bench files agree with each other.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "spindown/bridge_settings.hpp"
#include "spindown/doctor_check.hpp"

namespace spindown {

struct SerialPortInfo {
  std::string name;          // ttyACM0
  std::string device;        // /dev/ttyACM0
  std::string usb_serial;    // ATTRS{serial}; empty for boards without one (CH340 clones)
  std::string vendor_id;     // idVendor, e.g. 2341 (Arduino)
  std::string product_id;    // idProduct
  std::string manufacturer;
  std::string product;
  std::string usb_port;      // the USB device's kernel name = its port path, e.g. 1-1.2 (KERNELS==)
};

// USB serial ports under sysfs_class_tty (normally /sys/class/tty): each NAME/device walked up
// to the USB device (the directory holding idVendor), sorted by name. Ports without a USB device
// (ttyS*, consoles) are left out.
std::vector<SerialPortInfo> list_usb_serial_ports(const std::filesystem::path& sysfs_class_tty = "/sys/class/tty");

// The udev rule line for 99-spindown.rules naming this port's board bench:
//   SUBSYSTEM=="tty", ATTRS{serial}=="…", ENV{SPINDOWN_BENCH}="bench"   (by port path without a serial)
std::string udev_rule_line(const SerialPortInfo& port, const std::string& bench);

// What stat(2) says about a device path (following the udev symlink).
struct DeviceFacts {
  bool exists = false;
  std::string error;        // strerror when it does not
  std::string resolved;     // the device node the path leads to (/dev/ttyACM0)
  bool char_device = false;
  unsigned mode = 0;        // permission bits
  unsigned uid = 0, gid = 0;
  std::string owner_name, group_name;
};
DeviceFacts device_facts(const std::string& path);

// The service user and its groups (primary and supplementary), plus dialout, which the bridge
// unit grants with SupplementaryGroups=dialout.
struct ServiceUser {
  std::string name = "spindown";
  bool exists = false;
  unsigned uid = 0, gid = 0;
  std::vector<unsigned> groups;       // every gid the user is in
  std::optional<unsigned> dialout_gid;
};
ServiceUser lookup_service_user(const std::string& name);

// One bench's serial device: fail when it is missing and this PC runs the bench's bridge
// (bridge_enabled_here), or when the service user cannot read and write it; warn when the path is
// not the udev name /dev/spindown/<bench> the bridge unit's DeviceAllow= permits; skip when the
// device is missing and the bridge does not run here.
DoctorCheck check_serial_device(const std::string& bench, const std::string& device, const DeviceFacts& facts,
                                const ServiceUser& user, bool bridge_enabled_here);

// A bench file as the doctor found it: its name, and the settings or why they did not load.
struct BridgeBenchFile {
  std::string path;
  std::string stem;                        // file name without .toml = the unit's instance (bench id)
  std::optional<BridgeSettings> settings;  // nullopt: error says why
  std::string error;
};
// Reads every *.toml of a directory (sorted), or the files given. A file that does not load
// becomes a BridgeBenchFile with its error.
std::vector<BridgeBenchFile> read_bench_files(const std::vector<std::string>& files_or_dirs);

// The bench files together: fail for a file that does not load, for two benches on one device;
// warn when bench_id in a file differs from its file name (the unit's instance wins, so the
// bench would publish under the file name), or when no bench is configured.
std::vector<DoctorCheck> check_bench_files(const std::vector<BridgeBenchFile>& files, const std::string& where);

}  // namespace spindown
