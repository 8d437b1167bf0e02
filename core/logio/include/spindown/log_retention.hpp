#pragma once
// spindown-logger's retention: at most N log files, or at most a disk budget in bytes, deleting
// the oldest first and never the file being written. Only the logger's own files count and are
// ever deleted: names DIR/PREFIX-YYYY-MM-DD-HHMMSS[-BENCH][.N].lcm with its prefix and bench
// (event_log_writer.hpp), so another logger's files, copies renamed by hand and anything else
// in the directory are left alone. Oldest = earliest modification time (a closed log's is when
// it was closed), then name.
//
// The policy (files_to_prune) is a pure function of the listing; prune_log_files() lists the
// directory, applies it and unlinks.
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

struct LogRetentionOptions {
  std::int64_t keep_files = 0;   // at most this many files, the one being written included; 0 = no limit
  double keep_mb = 0;            // at most this many MB (1e6 bytes) in all, the one being written included; 0 = no limit

  bool enabled() const { return keep_files > 0 || keep_mb > 0; }
  bool is_valid(std::string* why) const;
};

struct LogFileInfo {
  std::string path;
  std::int64_t bytes = 0;
  std::int64_t mtime_ns = 0;
};

// The files to delete, oldest first, so that what is left keeps within both limits; never
// `current` (which counts towards them). When `current` alone is over the budget, every other
// file goes and it stays.
std::vector<LogFileInfo> files_to_prune(std::vector<LogFileInfo> files, std::string_view current,
                                        const LogRetentionOptions& options);

// True for a name (no directory) that the logger with this prefix and bench ("" = none) writes.
bool is_own_log_file_name(std::string_view name, std::string_view prefix, std::string_view bench);

struct LogPruneResult {
  std::vector<LogFileInfo> deleted;
  std::int64_t bytes_deleted = 0;
  std::int64_t bytes_kept = 0;         // the logger's files left, current included
  std::int64_t files_kept = 0;
  std::vector<std::string> errors;     // "cannot delete PATH: errno text", "cannot list DIR: …"
};

// Lists dir and deletes the logger's own files, oldest first and never `current`, one at a time
// until enough() says there is room (a disk about to fill, whatever the budget allows).
LogPruneResult free_log_space(const std::string& dir, std::string_view prefix, std::string_view bench,
                              const std::string& current, const std::function<bool()>& enough);

// Lists dir, deletes what files_to_prune says. current: the path being written (as the writer
// names it: dir + "/" + name).
LogPruneResult prune_log_files(const std::string& dir, std::string_view prefix, std::string_view bench,
                               const std::string& current, const LogRetentionOptions& options);

}  // namespace spindown
