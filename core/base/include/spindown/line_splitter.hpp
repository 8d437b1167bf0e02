#pragma once
// Assembles lines from the byte chunks a serial port delivers. Memory stays bounded whatever
// arrives: a line longer than the limit (a 10 MB burst with no newline, a wrong baud rate) is
// discarded up to its next newline and counted, never buffered.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace spindown {

class LineSplitter {
 public:
  // What feed() hands out: a complete line without "\n" (and without one trailing "\r"), or,
  // once per over-long line, its first max_line_bytes bytes with oversize = true.
  struct Line {
    std::string_view text;
    bool oversize = false;
  };
  using Handler = std::function<void(const Line&)>;

  explicit LineSplitter(std::size_t max_line_bytes = 1024);

  // Splits chunk at '\n'; calls on_line for each completed (or overflowing) line, in order.
  // The text view is only valid during the call.
  void feed(std::string_view chunk, const Handler& on_line);

  // Forgets a partial line (after a reconnect: its start came from another session).
  // Returns how many bytes were dropped.
  std::size_t reset();

  std::size_t max_line_bytes() const { return max_; }
  std::size_t buffered() const { return buf_.size(); }   // bytes of the partial line held
  std::uint64_t lines() const { return lines_; }          // complete lines handed out
  std::uint64_t oversize_lines() const { return oversize_; }
  std::uint64_t bytes_discarded() const { return discarded_; }  // bytes of over-long lines dropped

 private:
  std::size_t max_;
  std::string buf_;
  bool discarding_ = false;  // inside an over-long line: drop until the next '\n'
  std::uint64_t lines_ = 0, oversize_ = 0, discarded_ = 0;
};

}  // namespace spindown
