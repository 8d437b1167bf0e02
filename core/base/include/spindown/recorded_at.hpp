#pragma once
// When a recording was made, as its file tells (recording_time.hpp finds it), and that time as
// text: the report's and the baseline's dates.
#include <string>

namespace spindown {

struct RecordedAt {
  // Seconds since the epoch. A local time is counted as if it were UTC (timegm of its fields), so
  // that its calendar fields read back with gmtime: 14:03 local stays 14:03, never shifted by a
  // time zone nobody knows.
  double unix_s = 0;
  bool local = false;  // the recording PC's local time (PuTTY), not UTC
};

// "2024-09-14 14:03:22" (and " UTC" for a UTC time, " local time" for a local one when labelled).
std::string recorded_at_text(const RecordedAt& at, bool labelled = true);
// "2024-09-14".
std::string recorded_date_text(const RecordedAt& at);

}  // namespace spindown
