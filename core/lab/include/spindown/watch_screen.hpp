#pragma once
// One redraw of `spindown watch` on a terminal of a given size: the table first (its title,
// header and every bench row, which nothing below may push off the screen), then, in the rows
// left and at most max_events of them, the most recent events, each folded within the width (a
// long one takes at most two lines, the second cut with "…"). Every line fits the width; there
// are at most height − 1 of them, so that the terminal never scrolls the title away. A size of 0
// leaves that side unbounded.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "spindown/lab_table.hpp"

namespace spindown {

struct WatchScreenOptions {
  std::size_t width = 0, height = 0;  // the terminal's (TIOCGWINSZ); 0: unknown
  std::size_t max_events = 12;        // the event area's bound
};

std::string watch_screen(const LabTable& table, std::int64_t now_us, std::span<const std::string> recent_events,
                         const WatchScreenOptions& options);

// A line of text folded within width code points: at most max_lines lines, continuation lines
// indented by indent, the last cut with "…" when the text does not fit (never inside a character).
std::string fold_to_width(std::string_view line, std::size_t width, std::size_t max_lines, std::size_t indent = 4);

}  // namespace spindown
