#include "export_mcap.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <fstream>

#include "exit_codes.hpp"
#include "spindown/lcm_log_mcap.hpp"

namespace spindown::cli {

int run_export_mcap(const ExportCommandOptions& o) {
  // Written beside the target and renamed at the end, so a failed export leaves no half file.
  const std::string tmp = o.mcap + ".partial";
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) {
    fmt::print(stderr, "spindown export: cannot write {}: {}\n", o.mcap, std::strerror(errno));
    return exit_unusable;
  }
  LcmLogMcapResult r;
  try {
    r = write_lcm_log_mcap(o.log, out, {.bench_regex = o.bench_regex});
  } catch (const LcmLogMcapError& e) {
    out.close();
    std::remove(tmp.c_str());
    fmt::print(stderr, "spindown export: {}\n", e.what());
    return exit_unusable;
  }
  out.close();
  for (const auto& p : r.problems) fmt::print(stderr, "{}\n", p);
  if (r.problems_total > std::int64_t(r.problems.size()))
    fmt::print(stderr, "{}: {} more problems\n", o.log, r.problems_total - std::int64_t(r.problems.size()));
  if (!out) {
    std::remove(tmp.c_str());
    fmt::print(stderr, "spindown export: writing {} failed: {}\n", o.mcap, std::strerror(errno ? errno : EIO));
    return exit_unusable;
  }
  if (r.events == 0) {
    std::remove(tmp.c_str());
    fmt::print(stderr, "spindown export: {}: error: no LCM event in the file: not an LCM event log (--mcap reads "
                       "LCM logs; spindown-logger and lcm-logger write them)\n", o.log);
    return exit_unusable;
  }
  if (std::rename(tmp.c_str(), o.mcap.c_str()) != 0) {
    fmt::print(stderr, "spindown export: cannot rename {} to {}: {}\n", tmp, o.mcap, std::strerror(errno));
    std::remove(tmp.c_str());
    return exit_unusable;
  }
  fmt::print(stderr, "spindown export: {} samples, {} RUN, {} FIT messages on {} topics -> {} ({} bytes)\n",
             r.samples, r.runs, r.fits, r.channels, o.mcap, r.bytes);
  return exit_ok;
}

}  // namespace spindown::cli
