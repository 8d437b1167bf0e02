#pragma once
// The kernel's drops on a process's own UDP sockets (a full receive buffer): what the services'
// heartbeats report as udp_drops, and the backlog the fitter looks at before it calls a bench
// silent. Read from /proc; doctor's network checks use them too.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace spindown {

// Datagrams the kernel dropped on particular UDP sockets (a full receive buffer, a bad
// checksum): the `drops` column of /proc/net/udp and udp6, unlike RcvbufErrors, which counts
// every socket of the network namespace (another program's drops too).
struct UdpSocketDrops {
  std::size_t sockets = 0;  // sockets found among the inodes asked for
  std::int64_t drops = 0;   // their drops, summed
  std::int64_t queued_bytes = 0;  // their rx_queue: received by the kernel, not yet read
};
// From the text of /proc/net/udp or /proc/net/udp6: the lines whose inode is one of inodes.
UdpSocketDrops parse_udp_socket_drops(std::string_view proc_net_udp, const std::vector<std::uint64_t>& inodes);
// This process's own UDP sockets: the inodes of /proc/self/fd's "socket:[N]" links, looked up
// in /proc/self/net/udp and udp6. Nullopt when /proc cannot be read.
std::optional<UdpSocketDrops> own_udp_socket_drops();
// Their drops alone, -1 when /proc cannot be read: what the services' heartbeats and their last
// line on stderr report as udp_drops.
std::int64_t own_udp_drop_count();
// Bytes waiting in their receive queues, -1 when /proc cannot be read: the fitter judges no bench
// silent while datagrams wait there (after a freeze, SIGSTOP, its backlog is not silence).
std::int64_t own_udp_queued_bytes();

}  // namespace spindown
