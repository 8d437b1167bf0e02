#pragma once
// The lab a log was recorded for (issue 42): spindown-logger signs nothing into its files, but it
// records its own heartbeat (SPINDOWN.logger.STATUS), which carries the lab it serves and the
// group and port it listens on. A logger on a PC that serves two labs records both labs' traffic
// (Linux hands every group joined on a port to each socket on that port): a refit of its log must
// take that logger's lab, not the default one.
#include <cstdint>
#include <optional>
#include <string>

namespace spindown {

struct LogLab {
  std::string lab;      // the lab its logger served
  std::string sent_to;  // "group:port" the logger listened on ("" when it did not say)
};

// From the first logger heartbeat within max_events events of the log at path; nullopt when none
// (another program's log, lcm-logger's, a log from before the fields existed) or the file cannot
// be read (the refit itself says so).
std::optional<LogLab> log_lab(const std::string& path, std::int64_t max_events = 20000);

}  // namespace spindown
