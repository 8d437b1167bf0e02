// SerialPort over real pseudo-terminals (openpty), as wjwwood/serial tests its unix port.
#include <gtest/gtest.h>

#include <array>
#include <cerrno>
#include <pty.h>
#include <string>
#include <termios.h>
#include <unistd.h>

#include "spindown/pseudo_terminal.hpp"
#include "spindown/serial_port.hpp"

using namespace std::chrono_literals;
using spindown::SerialError;
using spindown::SerialPort;

namespace {
struct Pty {
  int master = -1, slave = -1;
  std::string path;
  Pty() {
    char name[128];
    if (::openpty(&master, &slave, name, nullptr, nullptr) != 0) throw std::runtime_error("openpty");
    path = name;
  }
  ~Pty() {
    if (master >= 0) ::close(master);
    if (slave >= 0) ::close(slave);
  }
};

std::string read_for(SerialPort& port, std::size_t want) {
  std::string got;
  std::array<char, 256> buf{};
  for (int i = 0; i < 100 && got.size() < want; ++i) got.append(buf.data(), port.read_some(buf, 20ms));
  return got;
}
}  // namespace

TEST(SerialPort, OpensRawAtTheBaudRate) {
  Pty pty;
  SerialPort port(pty.path, 115200);
  EXPECT_TRUE(port.is_open());
  termios tio{};
  ASSERT_EQ(::tcgetattr(port.fd(), &tio), 0);
  EXPECT_EQ(::cfgetispeed(&tio), speed_t(B115200));
  EXPECT_EQ(tio.c_lflag & (ICANON | ECHO), 0u);  // raw: no line editing, no echo
  EXPECT_EQ(tio.c_oflag & OPOST, 0u);
  EXPECT_EQ(tio.c_iflag & (ICRNL | IXON), 0u);   // CR stays CR, ^S/^Q are data
}

TEST(SerialPort, ReadsBytesUnchanged) {
  Pty pty;
  SerialPort port(pty.path, 9600);
  const std::string sent = "5234\t0.00\r\n\x13\x11\x03\xff";
  ASSERT_EQ(::write(pty.master, sent.data(), sent.size()), ssize_t(sent.size()));
  EXPECT_EQ(read_for(port, sent.size()), sent);
}

TEST(SerialPort, ReadTimesOutWithZero) {
  Pty pty;
  SerialPort port(pty.path, 9600);
  std::array<char, 16> buf{};
  EXPECT_EQ(port.read_some(buf, 10ms), 0u);
}

TEST(SerialPort, WritesReachTheOtherSide) {
  Pty pty;
  SerialPort port(pty.path, 115200);
  port.write_all("P5\n", 100ms);
  char buf[8] = {};
  ssize_t got = 0;
  for (int i = 0; i < 100 && got < 3; ++i) {
    const ssize_t n = ::read(pty.master, buf + got, sizeof buf - 1 - size_t(got));
    if (n > 0) got += n;
  }
  EXPECT_EQ(std::string(buf, size_t(got)), "P5\n");
}

TEST(SerialPort, MissingDeviceIsAClearError) {
  try {
    SerialPort port("/nonexistent/ttyACM9", 9600);
    FAIL() << "opened a missing device";
  } catch (const SerialError& e) {
    EXPECT_EQ(e.errno_value(), ENOENT);
    EXPECT_TRUE(e.disconnected());
    EXPECT_STREQ(e.what(), "cannot open /nonexistent/ttyACM9: No such file or directory");
  }
}

TEST(SerialPort, NotATerminalIsRefused) {
  try {
    SerialPort port("/dev/null", 9600);
    FAIL() << "configured /dev/null as a serial port";
  } catch (const SerialError& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/null is not a serial port"), std::string::npos) << e.what();
  }
}

TEST(SerialPort, UnsupportedBaudIsRefused) {
  Pty pty;
  EXPECT_THROW(SerialPort(pty.path, 12345), std::invalid_argument);
  EXPECT_TRUE(spindown::is_supported_baud(9600));
  EXPECT_FALSE(spindown::is_supported_baud(250000));
}

TEST(SerialPort, HangupIsADisconnect) {
  spindown::PseudoTerminal bench;
  SerialPort port(bench.slave_path(), 9600);
  ASSERT_TRUE(bench.wait_for_reader(1s));
  bench.write("1\t2.00\r\n", 100ms);
  EXPECT_EQ(read_for(port, 8), "1\t2.00\r\n");
  bench.close();  // the cable is pulled
  std::array<char, 16> buf{};
  bool disconnected = false;
  for (int i = 0; i < 50 && !disconnected; ++i) {
    try {
      port.read_some(buf, 20ms);
    } catch (const SerialError& e) {
      disconnected = e.disconnected();
    }
  }
  EXPECT_TRUE(disconnected);
}

TEST(SerialPort, MovedFromPortIsClosed) {
  Pty pty;
  SerialPort a(pty.path, 9600);
  SerialPort b = std::move(a);
  EXPECT_FALSE(a.is_open());  // NOLINT(bugprone-use-after-move): checking the moved-from state
  EXPECT_TRUE(b.is_open());
  std::array<char, 4> buf{};
  EXPECT_THROW(a.read_some(buf, 1ms), SerialError);
}

TEST(PseudoTerminal, SeesTheReaderAndItsBaud) {
  spindown::PseudoTerminal bench;
  EXPECT_FALSE(bench.reader_attached());
  {
    SerialPort port(bench.slave_path(), 9600);
    EXPECT_TRUE(bench.reader_attached());
    EXPECT_EQ(bench.reader_baud(), 9600);
  }
  EXPECT_FALSE(bench.reader_attached());
}
