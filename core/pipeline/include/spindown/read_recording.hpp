#pragma once
// One entry point for every recorded file the suite reads: detects the format (LCM event log
// by its magic word, else a spindown-v1 capture when its head has the firmware's banner or mostly
// its checksummed samples, else Arduino/PuTTY text when most lines are millis<TAB>volts samples,
// else delimited text) and returns one Recording per bench (text files: exactly one).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>

#include "spindown/arduino_text.hpp"
#include "spindown/delimited_text.hpp"
#include "spindown/file_bytes.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/recording.hpp"
#include "spindown/spindown_text.hpp"

namespace spindown {

enum class FileFormat { automatic, arduino_text, delimited_text, lcm_log, spindown_v1 };
// "auto", "arduino", "delimited", "lcm", "spindown-v1"
std::string_view file_format_name(FileFormat format);
std::optional<FileFormat> parse_file_format(std::string_view name);

struct ReadOptions {
  FileFormat format = FileFormat::automatic;
  ArduinoTextOptions arduino;
  DelimitedTextOptions delimited;  // naming a column or unit makes a text file delimited
  LcmLogOptions lcm;
  SpindownTextOptions spindown;
  bool is_valid(std::string* why) const;
};

// What read_recordings found beside each Recording (same order).
struct RecordingInfo {
  FileFormat format = FileFormat::automatic;
  std::string bench;               // LCM logs: the bench id; text: empty
  std::optional<config_t> config;  // LCM logs: the latest SPINDOWN.<bench>.CONFIG
  std::int64_t samples_lost = 0;   // LCM logs and spindown-v1 captures: from sequence gaps
};

// J and K_b of a recording's CONFIG (LCM logs) when it has a usable one; an unusable one is a
// warning in diags naming source. For choose_bench_params (bench_file.hpp).
std::optional<BenchParams> config_bench_params(const RecordingInfo* info, const std::string& source,
                                               std::vector<Diagnostic>& diags);

// Never throws for bad input: an unreadable or missing file gives one Recording whose error
// diagnostic names the file and the errno text; a file with nothing usable one with an error
// "no samples: …". Diagnostics about an LCM log as a whole are copied into every Recording.
std::vector<Recording> read_recordings(const std::string& path, const ReadOptions& options = {},
                                       std::vector<RecordingInfo>* info = nullptr);

// The format read_recordings would choose for these bytes (never automatic).
FileFormat detect_format(std::string_view head, const ReadOptions& options = {});

}  // namespace spindown
