#pragma once
// A pseudo-terminal pair seen from the device side: we hold the master, a program (the bridge)
// opens the slave path as if it were /dev/ttyACM0. The slave starts raw so bytes pass unchanged.
// Used by the virtual bench and by tests in place of hardware.
#include <chrono>
#include <memory>
#include <string>
#include <string_view>

namespace spindown {

class PseudoTerminal {
 public:
  // Opens a new pty (throws std::runtime_error with errno text on failure).
  PseudoTerminal();
  ~PseudoTerminal();
  PseudoTerminal(PseudoTerminal&& other) noexcept;
  PseudoTerminal& operator=(PseudoTerminal&& other) noexcept;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  const std::string& slave_path() const { return slave_path_; }
  int master_fd() const { return master_; }

  // True while some process has the slave open (the master sees no hangup).
  bool reader_attached() const;
  // Waits up to timeout for a reader; true when one is there.
  bool wait_for_reader(std::chrono::milliseconds timeout) const;
  // The baud rate the reader set on the slave (0 when unknown).
  int reader_baud() const;
  // Writes all of data within timeout; returns bytes written (fewer on timeout or hangup).
  std::size_t write(std::string_view data, std::chrono::milliseconds timeout);
  // Reads what the reader sent (non-blocking); empty when nothing.
  std::string read_available();
  void close();  // the "cable pulled": the reader sees a hangup
  // A stable name for the slave, as udev gives a board (/dev/spindown/bench-1): link (if not
  // empty) becomes a symlink to slave_path(), replacing an old one. Throws on failure.
  void link_as(const std::string& link) const;

 private:
  int master_ = -1;
  std::string slave_path_;
};

// A new pty for a simulated board that was just plugged in: linked as link (when not empty), its
// slave path printed on a line of stdout and flushed, which is how the benches tell their
// scripts where to connect. Throws as PseudoTerminal() does.
std::unique_ptr<PseudoTerminal> plug_in_pty(const std::string& link);

}  // namespace spindown
