#include "spindown/watch_screen.hpp"

#include <algorithm>
#include <vector>

#include "spindown/text_support.hpp"
#include "spindown/utf8_text.hpp"

namespace spindown {

std::string fold_to_width(std::string_view line, std::size_t width, std::size_t max_lines, std::size_t indent) {
  if (width == 0 || display_width(line) <= width) return std::string(line) + '\n';
  if (indent + 2 > width) indent = 0;
  std::string out;
  for (std::size_t n = 0; n < std::max<std::size_t>(max_lines, 1) && !line.empty(); ++n) {
    const std::size_t room = width - (n == 0 ? 0 : indent);
    const bool last = n + 1 >= max_lines;
    if (n > 0) out.append(indent, ' ');
    if (display_width(line) <= room) {
      out.append(line);
      out += '\n';
      break;
    }
    if (last) {
      out.append(line.substr(0, utf8_prefix_bytes(line, room - 1)));
      out += "…\n";
      break;
    }
    // Break at the last space that leaves something on this line, else mid-word.
    std::size_t cut = utf8_prefix_bytes(line, room);
    const std::size_t space = line.substr(0, cut + 1).rfind(' ');
    if (space != std::string_view::npos && space > 0) cut = space;
    out.append(line.substr(0, cut));
    out += '\n';
    line.remove_prefix(cut);
    while (!line.empty() && line.front() == ' ') line.remove_prefix(1);
  }
  return out;
}

std::string watch_screen(const LabTable& table, std::int64_t now_us, std::span<const std::string> recent_events,
                         const WatchScreenOptions& o) {
  // One column spare: a line exactly as wide as the terminal leaves some terminals waiting to wrap.
  const std::size_t width = o.width > 1 ? o.width - 1 : o.width;
  const std::size_t room = o.height > 1 ? o.height - 1 : (o.height == 0 ? static_cast<std::size_t>(-1) : 1);
  const std::string text = table.render(now_us, width);
  std::string out;
  std::size_t used = 0;
  text::for_each_line(text, [&](std::int64_t, std::string_view line) {
    if (used == room) return;
    out.append(line);
    out += '\n';
    ++used;
  });
  if (recent_events.empty() || used + 2 > room) return out;
  // The newest events that fit, oldest first, each at most two lines.
  std::vector<std::string> folded;
  std::size_t lines = 0;
  const std::size_t area = std::min(room - used - 1, o.max_events * 2);
  std::size_t shown = 0;
  for (auto it = recent_events.rbegin(); it != recent_events.rend() && shown < o.max_events; ++it, ++shown) {
    std::string f = fold_to_width("  " + *it, width, 2);
    const std::size_t n = static_cast<std::size_t>(std::count(f.begin(), f.end(), '\n'));
    if (lines + n > area) {
      if (lines + 1 <= area) folded.push_back(fold_to_width("  " + *it, width, 1)), lines += 1;
      break;
    }
    folded.push_back(std::move(f));
    lines += n;
  }
  if (folded.empty()) return out;
  out += "recent events:\n";
  for (auto it = folded.rbegin(); it != folded.rend(); ++it) out += *it;
  return out;
}

}  // namespace spindown
