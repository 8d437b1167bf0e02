#include "spindown/serial_port.hpp"

#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>
#include <utility>

namespace spindown {

namespace {

struct BaudName {
  int baud;
  speed_t constant;
};
constexpr BaudName kBauds[] = {
    {1200, B1200},       {2400, B2400},       {4800, B4800},       {9600, B9600},
    {19200, B19200},     {38400, B38400},     {57600, B57600},     {115200, B115200},
    {230400, B230400},   {460800, B460800},   {500000, B500000},   {576000, B576000},
    {921600, B921600},   {1000000, B1000000}, {1152000, B1152000}, {1500000, B1500000},
    {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000}, {3500000, B3500000},
    {4000000, B4000000},
};

bool speed_constant(int baud, speed_t& out) {
  for (const auto& b : kBauds)
    if (b.baud == baud) {
      out = b.constant;
      return true;
    }
  return false;
}

// Errors that mean the device itself went away rather than a bad request.
bool is_disconnect_errno(int err) { return err == EIO || err == ENXIO || err == ENODEV || err == EBADF || err == ENOENT; }

}  // namespace

bool is_supported_baud(int baud) {
  speed_t s;
  return speed_constant(baud, s);
}

SerialPort::SerialPort(const std::string& path, int baud) : path_(path), baud_(baud) {
  speed_t speed;
  if (!speed_constant(baud, speed)) throw std::invalid_argument(fmt::format("unsupported baud rate {}", baud));
  fd_ = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    const int err = errno;
    fail(fmt::format("cannot open {}: {}", path, std::strerror(err)), err, is_disconnect_errno(err));
  }
  termios tio{};
  if (::tcgetattr(fd_, &tio) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    fail(fmt::format("{} is not a serial port: {}", path, std::strerror(err)), err, false);
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;  // ignore modem lines, enable the receiver
  tio.c_cflag &= ~(CSTOPB | CRTSCTS | PARENB);
  tio.c_iflag &= ~(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  ::cfsetispeed(&tio, speed);
  ::cfsetospeed(&tio, speed);
  if (::tcsetattr(fd_, TCSANOW, &tio) != 0) {
    const int err = errno;
    ::close(fd_);
    fd_ = -1;
    fail(fmt::format("cannot configure {} at {} baud: {}", path, baud, std::strerror(err)), err, false);
  }
}

SerialPort::~SerialPort() { close(); }

SerialPort::SerialPort(SerialPort&& o) noexcept
    : fd_(std::exchange(o.fd_, -1)), path_(std::move(o.path_)), baud_(o.baud_) {}

SerialPort& SerialPort::operator=(SerialPort&& o) noexcept {
  if (this != &o) {
    close();
    fd_ = std::exchange(o.fd_, -1);
    path_ = std::move(o.path_);
    baud_ = o.baud_;
  }
  return *this;
}

void SerialPort::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void SerialPort::fail(const std::string& what, int err, bool disconnected) const {
  throw SerialError(what, err, disconnected);
}

std::size_t SerialPort::read_some(std::span<char> buf, std::chrono::milliseconds timeout) {
  if (fd_ < 0) fail(fmt::format("{}: port is not open", path_), EBADF, true);
  pollfd p{fd_, POLLIN, 0};
  const int n = ::poll(&p, 1, static_cast<int>(timeout.count()));
  if (n < 0) {
    if (errno == EINTR) return 0;  // a signal: let the caller check its stop flag
    const int err = errno;
    fail(fmt::format("poll on {} failed: {}", path_, std::strerror(err)), err, false);
  }
  if (n == 0) return 0;
  if (p.revents & POLLNVAL) fail(fmt::format("{}: descriptor no longer valid", path_), EBADF, true);
  if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
    const ssize_t got = ::read(fd_, buf.data(), buf.size());
    if (got > 0) return static_cast<std::size_t>(got);
    if (got < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
    const int err = got < 0 ? errno : EIO;
    fail(got < 0 ? fmt::format("{} disconnected: {}", path_, std::strerror(err))
                 : fmt::format("{} disconnected: end of file (device hung up)", path_),
         err, true);
  }
  return 0;
}

void SerialPort::write_all(std::string_view data, std::chrono::milliseconds timeout) {
  if (fd_ < 0) fail(fmt::format("{}: port is not open", path_), EBADF, true);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (int guard = 0; !data.empty() && guard < 1'000'000; ++guard) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() < 0) fail(fmt::format("write to {} timed out", path_), ETIMEDOUT, false);
    pollfd p{fd_, POLLOUT, 0};
    const int n = ::poll(&p, 1, static_cast<int>(left.count()));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      fail(fmt::format("poll on {} failed: {}", path_, std::strerror(err)), err, false);
    }
    if (n == 0) continue;
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) fail(fmt::format("{} disconnected", path_), EIO, true);
    const ssize_t put = ::write(fd_, data.data(), data.size());
    if (put < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      const int err = errno;
      fail(fmt::format("write to {} failed: {}", path_, std::strerror(err)), err, is_disconnect_errno(err));
    }
    data.remove_prefix(static_cast<std::size_t>(put));
  }
}

}  // namespace spindown
