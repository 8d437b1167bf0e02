#include "spindown/line_splitter.hpp"

#include <algorithm>

namespace spindown {

LineSplitter::LineSplitter(std::size_t max_line_bytes) : max_(std::max<std::size_t>(max_line_bytes, 1)) {
  buf_.reserve(max_);
}

void LineSplitter::feed(std::string_view chunk, const Handler& on_line) {
  while (!chunk.empty()) {
    const auto nl = chunk.find('\n');
    const auto piece = chunk.substr(0, nl);  // whole chunk when there is no newline
    if (discarding_) {
      discarded_ += piece.size();
    } else if (buf_.size() + piece.size() > max_) {
      // Over-long: hand out the start once so the caller can say what it was, drop the rest.
      const auto keep = max_ - buf_.size();
      buf_.append(piece.substr(0, keep));
      discarded_ += piece.size() - keep;
      ++oversize_;
      on_line(Line{buf_, true});
      buf_.clear();
      discarding_ = true;
    } else {
      buf_.append(piece);
    }
    if (nl == std::string_view::npos) return;
    // A newline ends the line (or the discarded one).
    if (discarding_) {
      discarding_ = false;
    } else {
      std::string_view line = buf_;
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      ++lines_;
      on_line(Line{line, false});
      buf_.clear();
    }
    chunk.remove_prefix(nl + 1);
  }
}

std::size_t LineSplitter::reset() {
  const auto dropped = buf_.size();
  buf_.clear();
  discarding_ = false;
  return dropped;
}

}  // namespace spindown
