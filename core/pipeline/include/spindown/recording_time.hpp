#pragma once
// When a file was recorded, as far as the file tells: a PuTTY log's header (the recording PC's
// clock, in its local time zone, which the file does not name) or an LCM log's receive times (the
// host's clock, seconds since the epoch: UTC). Used to date runs (report, drift over sessions) and
// baselines by the recording, never by the day the command runs.
#include <optional>
#include <string>
#include <string_view>

#include "spindown/read_recording.hpp"
#include "spindown/recorded_at.hpp"

namespace spindown {

// "=~=~=~ PuTTY log 2023.09.14 10:21:33 =~=~=~" → its date and time (local); nullopt when the text
// does not start with such a header.
std::optional<double> putty_log_time(std::string_view head);

// The file's start: its PuTTY header (text files), else its first event's receive time (LCM logs);
// nullopt when the file tells neither. format: detect_format's answer for the file's start
// (FileFormat::automatic: detected here).
std::optional<RecordedAt> recording_start(const std::string& path, FileFormat format = FileFormat::automatic,
                                          const ReadOptions& read = {});

}  // namespace spindown
