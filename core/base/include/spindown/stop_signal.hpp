#pragma once
// SIGINT and SIGTERM for every spindown program: "stop, cleanly". The handler sets one
// process-wide flag and writes a byte into a pipe, so a loop that waits on the pipe's read end
// (LcmLoop does, beside LCM's socket) wakes at once, whichever thread the kernel gave the
// signal to; anything else polls requested().
//
// One StopSignals at a time (a second one throws std::logic_error); it installs the handlers
// when made (SA_RESTART: a signal never makes another system call fail with EINTR) and puts
// the previous ones back when destroyed.
#include <chrono>

namespace spindown {

struct StopSignalOptions {
  bool ignore_sigpipe = false;  // also SIGPIPE ignored (a write to a closed pipe or pty is an error, not death)
};

class StopSignals {
 public:
  explicit StopSignals(StopSignalOptions options = {});
  ~StopSignals();
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

  // True once SIGINT or SIGTERM came (or request() was called).
  bool requested() const;
  // As a signal would: from any thread, or from a signal handler.
  void request();
  // Readable once a stop was requested (never read from: it stays readable).
  int fd() const;
  // Sleeps until t, or less when a stop is requested; true when it slept to t.
  bool sleep_until(std::chrono::steady_clock::time_point t) const;
  bool sleep_for(std::chrono::steady_clock::duration d) const {
    return sleep_until(std::chrono::steady_clock::now() + d);
  }
};

}  // namespace spindown
