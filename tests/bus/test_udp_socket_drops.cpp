// A process's own UDP drops: the `drops` column of /proc/net/udp for its own sockets only.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "spindown/udp_socket_drops.hpp"

using namespace spindown;

namespace {

// A UDP socket bound to 127.0.0.1 on a free port, closed at the end of the test.
struct UdpSocket {
  int fd = -1;
  sockaddr_in addr{};
  explicit UdpSocket(int rcvbuf = 0) {
    fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (rcvbuf > 0) ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    socklen_t len = sizeof addr;
    ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  }
  ~UdpSocket() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

TEST(UdpSocketDrops, ParsesTheDropsOfTheInodesAskedFor) {
  const std::string udp =
      "   sl  local_address rem_address   st tx_queue rx_queue tr tm->when retrnsmt   uid  timeout inode ref "
      "pointer drops\n"
      "  105: 00000000:1DF3 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 4242 2 "
      "0000000000000000 17\n"
      "  105: 00000000:1DF3 00000000:0000 07 00000000:00000000 00:00000000 00000000     0        0 4343 2 "
      "0000000000000000 900\n"
      "  212: 0100007F:0035 00000000:0000 07 00000000:00000000 00:00000000 00000000   101        0 4444 2 "
      "0000000000000000 3\n"
      "garbage line\n";
  const auto mine = parse_udp_socket_drops(udp, {4242, 4444, 99});
  EXPECT_EQ(mine.sockets, 2u);
  EXPECT_EQ(mine.drops, 20);  // not the 900 of the other program's socket on the same port
  EXPECT_EQ(parse_udp_socket_drops(udp, {}).sockets, 0u);
  EXPECT_EQ(parse_udp_socket_drops("", {4242}).drops, 0);
}

TEST(UdpSocketDrops, FindsOwnSocketWithNoDrops) {
  const auto before = own_udp_socket_drops();
  ASSERT_TRUE(before.has_value()) << "/proc/self/net/udp unreadable";
  UdpSocket s;
  ASSERT_GE(s.fd, 0);
  const auto after = own_udp_socket_drops();
  ASSERT_TRUE(after.has_value());
  EXPECT_EQ(after->sockets, before->sockets + 1);
  EXPECT_EQ(after->drops, before->drops);
}

TEST(UdpSocketDrops, CountsDropsOfAnOverflowingSocket) {
  UdpSocket receiver(1024);  // the kernel rounds it up to its minimum (a few kB)
  UdpSocket sender;
  ASSERT_GE(receiver.fd, 0);
  ASSERT_GE(sender.fd, 0);
  const auto before = own_udp_socket_drops();
  ASSERT_TRUE(before.has_value());
  const std::vector<char> payload(1000, 'x');
  int sent = 0;
  for (int i = 0; i < 200; ++i)  // never read: past the buffer, every datagram is dropped
    if (::sendto(sender.fd, payload.data(), payload.size(), 0, reinterpret_cast<const sockaddr*>(&receiver.addr),
                 sizeof receiver.addr) == static_cast<ssize_t>(payload.size()))
      ++sent;
  ASSERT_EQ(sent, 200);
  const auto after = own_udp_socket_drops();
  ASSERT_TRUE(after.has_value());
  EXPECT_GT(after->drops - before->drops, 100);
  EXPECT_LT(after->drops - before->drops, 200);  // the first few fit in the buffer
}
