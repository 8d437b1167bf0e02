#pragma once
// An LCM event log's samples, runs and fits as MCAP (mcap_writer.hpp) for Foxglove and
// PlotJuggler: JSON messages ("json" encoding) with a JSON Schema each ("jsonschema").
//
// Topics are the LCM channel names, one MCAP channel per bench and kind, in order of first
// appearance:
//   SPINDOWN.<bench>.SAMPLE  one message per sample (a plot needs one value per message), the
//       CSV's fields: {"bench","seq","device_time_s","host_time_s","value","unit","raw_adc",
//       "clock_epoch"}; every recorded sample, repeats and NaN included, as the CSV has them.
//       log_time = the sample's host time (host_time_us: when the bridge had the line), so
//       samples, RUN and FIT share the host's wall clock; publish_time = the SAMPLE message's
//       utime. The device clock stays in "device_time_s" (PlotJuggler and Foxglove can plot
//       against a field). A sample without a host time takes the event's log time.
//   SPINDOWN.<bench>.RUN     each run_t as recorded: {"bench","run","state","state_code",
//       "t_cut_s","t_stop_s","first_seq","last_seq","samples","note","lead_in"}
//   SPINDOWN.<bench>.FIT     each fit_t as recorded, as `spindown fit --json` prints a run
//       (fit_message_json: "run","t_cut_s","models":[{"name","params":{"c1":{"value",
//       "stderr","unit"}…},"rmse",…}],"best",…,"bench":{…,"id"},"first_seq","last_seq")
//   RUN and FIT: log_time = the event's receive time in the log, publish_time = the message's
//   utime (the fitter's clock).
// Non-finite numbers are null (JSON has no NaN). MCAP sequence: the sample's seq (mod 2^32),
// else a per-channel count.
#include <cstdint>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace spindown {

struct LcmLogMcapOptions {
  std::string bench_regex = ".*";       // only benches whose id matches (whole id)
  std::size_t chunk_bytes = 1u << 20;   // McapWriterOptions::chunk_bytes
  std::size_t max_problems = 20;        // listed one by one; the rest are counted
};

struct LcmLogMcapResult {
  std::int64_t events = 0;               // events read from the log
  std::int64_t samples = 0, runs = 0, fits = 0;  // MCAP messages written, by kind
  std::int64_t channels = 0;
  std::int64_t problems_total = 0;       // events that could not be used, damage in the file
  std::vector<std::string> problems;     // "LOG: event N (CHANNEL) at byte X: what"
  std::uint64_t bytes = 0;               // the MCAP file's size
};

// The log cannot be opened: the message names it and says why.
class LcmLogMcapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads the log at log_path once, front to back, and writes the whole MCAP file to out.
LcmLogMcapResult write_lcm_log_mcap(const std::string& log_path, std::ostream& out, const LcmLogMcapOptions& options = {});

// The JSON Schemas of the three message kinds, as written into the file.
extern const char* const mcap_sample_json_schema;
extern const char* const mcap_run_json_schema;
extern const char* const mcap_fit_json_schema;

}  // namespace spindown
