#pragma once
// Progress of a long job (a refit of a big log, a report of many files) on a terminal: one
// line on stderr, "label  done / total (pct)  rate  ETA  extra", redrawn in place at most
// ten times a second and erased at the end. Only when the stream is a terminal: a pipe or a
// file (tests, scripts, CI) gets nothing, so output stays clean and diffable.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace spindown {

class ProgressReporter {
 public:
  enum class Unit { bytes, messages };
  using Clock = std::function<double()>;  // monotonic seconds; empty = steady_clock

  // enabled false (or fd not a terminal, checked by the caller with is_terminal) = silent.
  ProgressReporter(int fd, bool enabled, Unit unit = Unit::bytes, double min_interval_s = 0.1, Clock clock = {});
  ~ProgressReporter();
  ProgressReporter(const ProgressReporter&) = delete;
  ProgressReporter& operator=(const ProgressReporter&) = delete;

  static bool is_terminal(int fd);

  // Throttled: draws only when min_interval_s has passed since the last draw (or the start,
  // so jobs shorter than that never draw). extra is shown as given ("runs 3/10").
  void update(std::int64_t done, std::int64_t total, std::string_view label, std::string_view extra = {});
  // Erases the line now (before other output to the same stream); the next update redraws.
  void clear();
  // Erases the line for good; later updates are ignored.
  void finish();

  bool enabled() const { return enabled_; }
  int draws() const { return draws_; }

  // The line itself (no control characters), cut to width columns (0 = no limit).
  static std::string format_line(std::string_view label, std::int64_t done, std::int64_t total, Unit unit,
                                 std::string_view extra, double elapsed_s, std::size_t width);

 private:
  void write_raw(std::string_view text);
  double now() const;

  int fd_;
  bool enabled_;
  Unit unit_;
  double min_interval_s_;
  Clock clock_;
  double start_ = 0, last_draw_ = 0;
  bool shown_ = false;
  int draws_ = 0;
};

}  // namespace spindown
