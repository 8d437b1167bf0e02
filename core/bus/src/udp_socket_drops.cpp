#include "spindown/udp_socket_drops.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <dirent.h>
#include <fstream>
#include <sstream>
#include <string>
#include <unistd.h>

namespace spindown {

UdpSocketDrops parse_udp_socket_drops(std::string_view text, const std::vector<std::uint64_t>& inodes) {
  // "sl local_address rem_address st tx_queue:rx_queue tr:tm->when retrnsmt uid timeout inode
  // ref pointer drops": the inode is the 10th word, drops the 13th.
  UdpSocketDrops out;
  std::istringstream lines{std::string(text)};
  for (std::string line; std::getline(lines, line);) {
    std::istringstream fields(line);
    std::vector<std::string> w;
    for (std::string f; fields >> f;) w.push_back(f);
    if (w.size() < 13) continue;
    std::uint64_t inode = 0;
    const auto [p, ec] = std::from_chars(w[9].data(), w[9].data() + w[9].size(), inode);
    if (ec != std::errc() || p != w[9].data() + w[9].size()) continue;  // the header
    if (std::find(inodes.begin(), inodes.end(), inode) == inodes.end()) continue;
    ++out.sockets;
    out.drops += std::atoll(w[12].c_str());
    // "tx_queue:rx_queue", both hexadecimal.
    if (const auto colon = w[4].find(':'); colon != std::string::npos)
      out.queued_bytes += std::strtoll(std::string(w[4].substr(colon + 1)).c_str(), nullptr, 16);
  }
  return out;
}

std::optional<UdpSocketDrops> own_udp_socket_drops() {
  std::vector<std::uint64_t> inodes;
  DIR* dir = ::opendir("/proc/self/fd");
  if (!dir) return std::nullopt;
  while (const dirent* e = ::readdir(dir)) {
    char link[64] = {};
    const ssize_t n = ::readlinkat(::dirfd(dir), e->d_name, link, sizeof link - 1);
    unsigned long long inode = 0;
    if (n > 0 && std::sscanf(link, "socket:[%llu]", &inode) == 1) inodes.push_back(inode);
  }
  ::closedir(dir);
  UdpSocketDrops total;
  bool read_any = false;
  for (const char* path : {"/proc/self/net/udp", "/proc/self/net/udp6"}) {
    std::ifstream in(path);
    if (!in) continue;
    read_any = true;
    std::ostringstream text;
    text << in.rdbuf();
    const UdpSocketDrops d = parse_udp_socket_drops(text.str(), inodes);
    total.sockets += d.sockets;
    total.drops += d.drops;
    total.queued_bytes += d.queued_bytes;
  }
  if (!read_any) return std::nullopt;
  return total;
}

std::int64_t own_udp_drop_count() {
  const auto d = own_udp_socket_drops();
  return d ? d->drops : -1;
}

std::int64_t own_udp_queued_bytes() {
  const auto d = own_udp_socket_drops();
  return d ? d->queued_bytes : -1;
}

}  // namespace spindown
