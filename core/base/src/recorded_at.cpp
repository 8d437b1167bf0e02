#include "spindown/recorded_at.hpp"

#include <cmath>
#include <ctime>

namespace spindown {

namespace {

std::tm fields_of(double unix_s) {
  const std::time_t t = static_cast<std::time_t>(std::floor(unix_s));
  std::tm tm{};
  gmtime_r(&t, &tm);
  return tm;
}

}  // namespace

std::string recorded_at_text(const RecordedAt& at, bool labelled) {
  const std::tm tm = fields_of(at.unix_s);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S", &tm);
  return std::string(buf) + (!labelled ? "" : at.local ? " local time" : " UTC");
}

std::string recorded_date_text(const RecordedAt& at) {
  const std::tm tm = fields_of(at.unix_s);
  char buf[16];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", &tm);
  return buf;
}

}  // namespace spindown
