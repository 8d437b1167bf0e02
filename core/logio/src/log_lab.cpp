#include "spindown/log_lab.hpp"

#include <spindown/status_t.hpp>

#include "spindown/lcm_log_reader.hpp"
#include "spindown/message_decode.hpp"

namespace spindown {

std::optional<LogLab> log_lab(const std::string& path, std::int64_t max_events) {
  LcmLogReader reader(path, LcmSamples::view_only);
  if (!reader.good()) return std::nullopt;
  LcmLogEvent ev;
  for (std::int64_t n = 0; n < max_events && reader.next(ev); ++n) {
    if (ev.kind != LcmLogEvent::Kind::other || !ev.channel.ends_with(".STATUS") || ev.data_size <= 0) continue;
    MessageTrailer t;
    if (!read_message_trailer(ev.data, ev.data_size, t) || t.type != "status_t" || t.lab.empty()) continue;
    status_t s{};
    if (!decode_message(s, ev.data, ev.data_size) || s.service != "logger") continue;
    return LogLab{std::string(t.lab), std::string(t.sent_to)};
  }
  return std::nullopt;
}

}  // namespace spindown
