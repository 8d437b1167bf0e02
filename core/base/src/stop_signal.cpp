#include "spindown/stop_signal.hpp"

#include <atomic>
#include <cerrno>
#include <csignal>
#include <fcntl.h>
#include <ctime>
#include <poll.h>
#include <stdexcept>
#include <unistd.h>

namespace spindown {

namespace {

static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler's flag must be lock-free");
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler's pipe must be lock-free");

// The handler may only touch lock-free atomics and call async-signal-safe functions (write).
std::atomic<bool> g_installed{false};
std::atomic<bool> g_requested{false};
std::atomic<int> g_pipe_write{-1};
int g_pipe_read = -1;
struct sigaction g_old_int {}, g_old_term {}, g_old_pipe {};
bool g_ignored_pipe = false;

void wake() {
  const int fd = g_pipe_write.load();
  if (fd < 0) return;
  const int saved = errno;
  const char byte = 's';
  [[maybe_unused]] const ssize_t n = ::write(fd, &byte, 1);  // full pipe: already readable
  errno = saved;
}

extern "C" void on_stop_signal(int) {
  g_requested.store(true);
  wake();
}

}  // namespace

StopSignals::StopSignals(StopSignalOptions options) {
  if (g_installed.exchange(true)) throw std::logic_error("StopSignals: only one at a time");
  int p[2];
  if (::pipe2(p, O_CLOEXEC | O_NONBLOCK) != 0) {
    g_installed = false;
    throw std::runtime_error("StopSignals: cannot make a pipe");
  }
  g_pipe_read = p[0];
  g_pipe_write.store(p[1]);
  g_requested.store(false);
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  ::sigaction(SIGINT, &sa, &g_old_int);
  ::sigaction(SIGTERM, &sa, &g_old_term);
  g_ignored_pipe = options.ignore_sigpipe;
  if (g_ignored_pipe) {
    struct sigaction ign {};
    ign.sa_handler = SIG_IGN;
    sigemptyset(&ign.sa_mask);
    ::sigaction(SIGPIPE, &ign, &g_old_pipe);
  }
}

StopSignals::~StopSignals() {
  ::sigaction(SIGINT, &g_old_int, nullptr);
  ::sigaction(SIGTERM, &g_old_term, nullptr);
  if (g_ignored_pipe) ::sigaction(SIGPIPE, &g_old_pipe, nullptr);
  const int w = g_pipe_write.exchange(-1);
  ::close(w);
  ::close(g_pipe_read);
  g_pipe_read = -1;
  g_installed.store(false);
}

bool StopSignals::requested() const { return g_requested.load(); }

void StopSignals::request() {
  g_requested.store(true);
  wake();
}

int StopSignals::fd() const { return g_pipe_read; }

bool StopSignals::sleep_until(std::chrono::steady_clock::time_point t) const {
  for (;;) {
    if (requested()) return false;
    const auto now = std::chrono::steady_clock::now();
    if (now >= t) return true;
    // ppoll: to the nanosecond, as a plain sleep would be.
    const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(t - now).count();
    const timespec ts{static_cast<time_t>(left / 1'000'000'000), static_cast<long>(left % 1'000'000'000)};
    pollfd p{g_pipe_read, POLLIN, 0};
    ::ppoll(&p, 1, &ts, nullptr);
  }
}

}  // namespace spindown
