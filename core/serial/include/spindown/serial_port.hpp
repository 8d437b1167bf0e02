#pragma once
// One RAII serial port: opened raw (O_NOCTTY, cfmakeraw, 8N1, no flow control) at a standard
// baud rate; reads and writes wait with poll() and a timeout, never forever. Errors are
// SerialError with the device path and the errno text. A device that goes away (USB cable
// pulled, pty master closed) shows as SerialError with disconnected() true.
#include <chrono>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace spindown {

class SerialError : public std::runtime_error {
 public:
  SerialError(const std::string& what, int errno_value, bool disconnected)
      : std::runtime_error(what), errno_(errno_value), disconnected_(disconnected) {}
  int errno_value() const { return errno_; }
  bool disconnected() const { return disconnected_; }  // the device is gone: reopen later

 private:
  int errno_;
  bool disconnected_;
};

// True for the rates termios offers by name (1200 … 4000000).
bool is_supported_baud(int baud);

class SerialPort {
 public:
  SerialPort() = default;
  // Opens and configures; throws SerialError ("cannot open /dev/ttyACM0: No such file or
  // directory") or std::invalid_argument for an unsupported baud rate.
  SerialPort(const std::string& path, int baud);
  ~SerialPort();
  SerialPort(SerialPort&& other) noexcept;
  SerialPort& operator=(SerialPort&& other) noexcept;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  bool is_open() const { return fd_ >= 0; }
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  int baud() const { return baud_; }

  // Waits up to timeout for bytes, reads what is there (at most buf.size()); 0 on timeout.
  // Throws SerialError when the device hung up or failed.
  std::size_t read_some(std::span<char> buf, std::chrono::milliseconds timeout);
  // Writes all of data within timeout; throws SerialError on failure or timeout.
  void write_all(std::string_view data, std::chrono::milliseconds timeout);
  void close();

 private:
  [[noreturn]] void fail(const std::string& what, int err, bool disconnected) const;
  int fd_ = -1;
  std::string path_;
  int baud_ = 0;
};

}  // namespace spindown
