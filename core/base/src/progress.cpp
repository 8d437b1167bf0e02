#include "spindown/progress.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

namespace spindown {

namespace {

std::string amount(double x, ProgressReporter::Unit unit) {
  if (unit == ProgressReporter::Unit::messages) return fmt::format("{:.0f}", x);
  if (x < 1e3) return fmt::format("{:.0f} B", x);
  if (x < 1e6) return fmt::format("{:.1f} kB", x / 1e3);
  if (x < 1e9) return fmt::format("{:.1f} MB", x / 1e6);
  return fmt::format("{:.2f} GB", x / 1e9);
}

std::string duration(double s) {
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) return fmt::format("{:.0f} s", s);
  if (s < 3600) return fmt::format("{:.0f} min {:02.0f} s", std::floor(s / 60), std::fmod(s, 60));
  return fmt::format("{:.0f} h {:02.0f} min", std::floor(s / 3600), std::fmod(s / 60, 60));
}

std::size_t terminal_width(int fd) {
  winsize ws{};
  if (::ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
  return 80;
}

}  // namespace

ProgressReporter::ProgressReporter(int fd, bool enabled, Unit unit, double min_interval_s, Clock clock)
    : fd_(fd), enabled_(enabled), unit_(unit), min_interval_s_(min_interval_s), clock_(std::move(clock)) {
  start_ = last_draw_ = now();
}

ProgressReporter::~ProgressReporter() { finish(); }

bool ProgressReporter::is_terminal(int fd) { return ::isatty(fd) == 1; }

double ProgressReporter::now() const {
  if (clock_) return clock_();
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void ProgressReporter::write_raw(std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd_, text.data(), text.size());
    if (n <= 0) return;  // a terminal that went away: progress is not worth an error
    text.remove_prefix(static_cast<std::size_t>(n));
  }
}

std::string ProgressReporter::format_line(std::string_view label, std::int64_t done, std::int64_t total, Unit unit,
                                          std::string_view extra, double elapsed_s, std::size_t width) {
  std::string line(label);
  const double d = static_cast<double>(std::max<std::int64_t>(done, 0));
  if (total > 0) {
    const double t = static_cast<double>(total);
    line += fmt::format("  {} / {} ({:.0f} %)", amount(d, unit), amount(t, unit), 100 * std::min(d / t, 1.0));
  } else {
    line += fmt::format("  {}", amount(d, unit));
  }
  if (elapsed_s > 0 && d > 0) {
    const double rate = d / elapsed_s;
    line += fmt::format("  {}/s", amount(rate, unit));
    if (total > 0) line += fmt::format("  ETA {}", duration((static_cast<double>(total) - d) / rate));
  }
  if (!extra.empty()) line += fmt::format("  {}", extra);
  if (width > 0 && line.size() > width) line.resize(width);
  return line;
}

void ProgressReporter::update(std::int64_t done, std::int64_t total, std::string_view label, std::string_view extra) {
  if (!enabled_) return;
  const double t = now();
  if (t - last_draw_ < min_interval_s_) return;
  last_draw_ = t;
  const std::size_t width = terminal_width(fd_);
  const std::string line = format_line(label, done, total, unit_, extra, t - start_, width > 1 ? width - 1 : 0);
  write_raw("\r" + line + "\x1b[K");
  shown_ = true;
  ++draws_;
}

void ProgressReporter::clear() {
  if (!shown_) return;
  write_raw("\r\x1b[K");
  shown_ = false;
}

void ProgressReporter::finish() {
  clear();
  enabled_ = false;
}

}  // namespace spindown
