#include "spindown/pseudo_terminal.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <filesystem>
#include <fmt/format.h>
#include <poll.h>
#include <stdexcept>
#include <stdlib.h>
#include <termios.h>
#include <thread>
#include <unistd.h>
#include <utility>

namespace spindown {

namespace {
[[noreturn]] void fail(const char* what) {
  throw std::runtime_error(fmt::format("pseudo-terminal: {}: {}", what, std::strerror(errno)));
}

int baud_of(speed_t s) {
  struct Pair {
    speed_t s;
    int baud;
  };
  static constexpr Pair pairs[] = {{B1200, 1200},       {B2400, 2400},       {B4800, 4800},
                                   {B9600, 9600},       {B19200, 19200},     {B38400, 38400},
                                   {B57600, 57600},     {B115200, 115200},   {B230400, 230400},
                                   {B460800, 460800},   {B500000, 500000},   {B921600, 921600},
                                   {B1000000, 1000000}, {B2000000, 2000000}};
  for (const auto& p : pairs)
    if (p.s == s) return p.baud;
  return 0;
}
}  // namespace

PseudoTerminal::PseudoTerminal() {
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (master_ < 0) fail("posix_openpt");
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
    const int err = errno;
    ::close(master_);
    errno = err;
    fail("grantpt/unlockpt");
  }
  char name[128];
  if (::ptsname_r(master_, name, sizeof name) != 0) {
    const int err = errno;
    ::close(master_);
    errno = err;
    fail("ptsname_r");
  }
  slave_path_ = name;
  // Make the line discipline raw (no echo, no CR/LF mangling) before anyone writes.
  const int slave = ::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC);
  if (slave < 0) {
    const int err = errno;
    ::close(master_);
    errno = err;
    fail("open slave");
  }
  termios tio{};
  if (::tcgetattr(slave, &tio) == 0) {
    ::cfmakeraw(&tio);
    ::tcsetattr(slave, TCSANOW, &tio);
  }
  ::close(slave);  // from now on a hangup on the master means "no reader"
  ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
}

PseudoTerminal::~PseudoTerminal() { close(); }

PseudoTerminal::PseudoTerminal(PseudoTerminal&& o) noexcept
    : master_(std::exchange(o.master_, -1)), slave_path_(std::move(o.slave_path_)) {}

PseudoTerminal& PseudoTerminal::operator=(PseudoTerminal&& o) noexcept {
  if (this != &o) {
    close();
    master_ = std::exchange(o.master_, -1);
    slave_path_ = std::move(o.slave_path_);
  }
  return *this;
}

void PseudoTerminal::close() {
  if (master_ >= 0) ::close(master_);
  master_ = -1;
}

bool PseudoTerminal::reader_attached() const {
  if (master_ < 0) return false;
  pollfd p{master_, POLLOUT, 0};
  if (::poll(&p, 1, 0) < 0) return false;
  return (p.revents & POLLHUP) == 0;
}

bool PseudoTerminal::wait_for_reader(std::chrono::milliseconds timeout) const {
  // The master gives no event when the slave opens, so look every few milliseconds.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (int guard = 0; guard < 10'000'000; ++guard) {
    if (reader_attached()) return true;
    if (std::chrono::steady_clock::now() >= deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

int PseudoTerminal::reader_baud() const {
  if (master_ < 0) return 0;
  termios tio{};
  if (::tcgetattr(master_, &tio) != 0) return 0;
  return baud_of(::cfgetispeed(&tio));
}

std::size_t PseudoTerminal::write(std::string_view data, std::chrono::milliseconds timeout) {
  std::size_t done = 0;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (int guard = 0; done < data.size() && guard < 1'000'000 && master_ >= 0; ++guard) {
    const ssize_t put = ::write(master_, data.data() + done, data.size() - done);
    if (put > 0) {
      done += static_cast<std::size_t>(put);
      continue;
    }
    if (put < 0 && errno != EAGAIN && errno != EINTR) break;
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{master_, POLLOUT, 0};
    ::poll(&p, 1, static_cast<int>(std::min<long>(left.count(), 50)));
  }
  return done;
}

std::string PseudoTerminal::read_available() {
  std::string out;
  char buf[512];
  for (int guard = 0; guard < 1000 && master_ >= 0; ++guard) {
    const ssize_t got = ::read(master_, buf, sizeof buf);
    if (got <= 0) break;
    out.append(buf, static_cast<std::size_t>(got));
  }
  return out;
}

void PseudoTerminal::link_as(const std::string& link) const {
  if (link.empty()) return;
  std::error_code ec;
  std::filesystem::remove(link, ec);
  std::filesystem::create_symlink(slave_path_, link);
}

std::unique_ptr<PseudoTerminal> plug_in_pty(const std::string& link) {
  auto pty = std::make_unique<PseudoTerminal>();
  pty->link_as(link);
  std::fputs((pty->slave_path() + '\n').c_str(), stdout);
  std::fflush(stdout);
  return pty;
}

}  // namespace spindown
