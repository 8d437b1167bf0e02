#include "spindown/recording_time.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>

#include "spindown/lcm_log_reader.hpp"

namespace spindown {

namespace {

// The first bytes of a file (for the PuTTY header); "" when it cannot be read.
std::string file_head(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string s(n, '\0');
  in.read(s.data(), static_cast<std::streamsize>(n));
  s.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return s;
}

// Receive time of the log's first event with a time set (seconds since the epoch), as
// LcmLogReader finds it among the first few events (it resynchronises past damage at the start).
std::optional<double> lcm_log_start(const std::string& path) {
  LcmLogReader reader(path);
  if (!reader.good()) return std::nullopt;
  LcmLogEvent ev;
  for (int i = 0; i < 64 && reader.next(ev); ++i)
    if (ev.number > 0 && ev.log_utime > 0) return static_cast<double>(ev.log_utime) * 1e-6;
  return std::nullopt;
}


}  // namespace

std::optional<double> putty_log_time(std::string_view head) {
  const auto at = head.find("PuTTY log ");
  if (at == std::string_view::npos || head.substr(0, at).find('\n') != std::string_view::npos) return std::nullopt;
  std::tm tm{};
  int year = 0, month = 0, day = 0, hour = 0, minute = 0, second = 0;
  const std::string text(head.substr(at + 10, 19));
  if (std::sscanf(text.c_str(), "%4d.%2d.%2d %2d:%2d:%2d", &year, &month, &day, &hour, &minute, &second) != 6)
    return std::nullopt;
  if (month < 1 || month > 12 || day < 1 || day > 31 || hour > 23 || minute > 59 || second > 60) return std::nullopt;
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  tm.tm_sec = second;
  return static_cast<double>(timegm(&tm));
}

std::optional<RecordedAt> recording_start(const std::string& path, FileFormat format, const ReadOptions& read) {
  const std::string head = file_head(path, 512);
  if (head.empty()) return std::nullopt;
  if (format == FileFormat::automatic) format = detect_format(head, read);
  if (format == FileFormat::lcm_log) {
    if (auto t = lcm_log_start(path)) return RecordedAt{*t, false};
  } else if (format == FileFormat::arduino_text || format == FileFormat::spindown_v1) {
    if (auto t = putty_log_time(head)) return RecordedAt{*t, true};
  }
  return std::nullopt;
}

}  // namespace spindown
