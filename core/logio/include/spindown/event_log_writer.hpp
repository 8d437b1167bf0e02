#pragma once
// Writes standard LCM event logs (lcm_eventlog_t in "w" mode, so lcm-logplayer, lcm::LogFile
// readers and LcmLogReader accept them) the way spindown-logger needs, without threads or LCM
// subscriptions so tests can drive it with their own clock:
//
// - file names DIR/PREFIX-YYYY-MM-DD-HHMMSS[-BENCH][.N].lcm (local time; .N only when the name
//   is taken — an existing file is never overwritten);
// - rotation by size and by time, always between two events (an event is never split);
// - events are buffered and handed to the kernel only in whole events (flush() or a full
//   buffer), so a process killed with SIGKILL leaves a log that ends on an event boundary and
//   holds everything up to the last flush;
// - a status_t event on the status channel at the start and end of every file, after a write
//   error and at exit, so the log itself says what the logger saw (events, drops, errors);
// - sequence gaps of samples_t per bench (what it can see of loss upstream of the logger);
// - a full disk (ENOSPC, EDQUOT) keeps the file: what did not fit is cut off at the last whole
//   event (the file stays a valid log), events are counted as lost while the disk stays full
//   (state "disk full", one error naming the file), and every reopen_interval_s a status event
//   tries whether space is back; then writing goes on in the same file;
// - other write errors (directory removed, I/O error) are counted with the path and errno text;
//   the file is closed and a new one tried every reopen_interval_s;
// - retention (log_retention.hpp): with keep_files or keep_mb set, the oldest of its own files
//   are deleted when a file is opened and every prune_interval_s, never the file being written;
//   and before a flush would not fit on the disk, its oldest files go until it does, whatever the
//   budget allows (a --keep-mb above the free space never loses events while its old files
//   stay).
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include <spindown/status_t.hpp>

#include "spindown/lcm_status.hpp"
#include "spindown/log_retention.hpp"
#include "spindown/reorder_window.hpp"

struct _lcm_eventlog_t;

namespace spindown {

struct EventLogWriterOptions {
  std::string dir = ".";
  std::string prefix = "spindown";
  std::string bench;                       // optional: part of every file name
  double rotate_size_mb = 0;               // start a new file past this size (MB = 1e6 bytes); 0 = never
  double rotate_time_s = 0;                // start a new file after this long; 0 = never
  bool sync_on_flush = false;              // fdatasync at every flush (always at rotation and close)
  std::string status_channel = "SPINDOWN.logger.STATUS";
  std::string instance;                    // status_t.instance; empty = bench, else prefix
  std::size_t buffer_bytes = 1 << 20;      // events buffered before they go to the kernel
  std::size_t max_tracked_benches = 1024;  // benches (bridge sessions) whose sample sequence is followed
  double reopen_interval_s = 1.0;          // after a write error, wait before trying a new file
  LogRetentionOptions retention;           // old files deleted past these limits (none by default)
  double prune_interval_s = 10.0;          // retention is applied at least this often (and at each new file)

  bool is_valid(std::string* why) const;
};

// A log file could not be created: the message names the path and the errno text.
class EventLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct EventLogCounters {
  std::int64_t events = 0;           // events received and written
  std::int64_t bytes = 0;            // bytes written (events + the logger's own status events)
  std::int64_t files = 0;            // files opened
  std::int64_t flushes = 0;          // flushes that handed data to the kernel
  std::int64_t write_errors = 0;     // failed writes, flushes, syncs and opens
  std::int64_t events_lost = 0;      // events that may not be on disk because of write errors
  std::int64_t queue_drops = 0;      // events dropped before the writer (queue full), reported to it
  std::int64_t status_events = 0;    // the logger's own status events written into the logs
  std::int64_t decode_errors = 0;    // SAMPLE events that did not decode as samples_t (still logged)
  // By sequence number, with the fitter's reorder window (reorder_window.hpp): a message past a
  // gap waits for the gap to fill; only what never came within the window is missing.
  std::int64_t seq_gaps = 0;         // gaps in the sequence numbers not filled within the window
  std::int64_t samples_missing = 0;  // samples missing by sequence number (less those that came late)
  std::int64_t samples_late = 0;     // samples that came after their gap was counted (in the log all the same)
  std::int64_t seq_repeats = 0;      // samples whose sequence number was already seen (a duplicate, a restart)
  std::int64_t benches_untracked = 0;// SAMPLE messages of benches beyond max_tracked_benches
  std::int64_t disk_full_episodes = 0;  // times the disk filled up (each one write error)
  std::int64_t oversize_drops = 0;   // events larger than the recorder's max_event_bytes, not recorded
  std::int64_t files_deleted = 0;    // old log files deleted by retention
  std::int64_t files_deleted_for_space = 0;  // of those, deleted because the disk was about to fill
  std::int64_t bytes_deleted = 0;    // and their bytes
  std::int64_t retention_errors = 0; // files retention could not delete (or list)
};

// File name for a log opened at unix_time (local time), without the directory; suffix 0 = none.
std::string event_log_file_name(std::string_view prefix, std::string_view bench, std::time_t unix_time,
                                int suffix = 0);

class EventLogWriter {
 public:
  // options must be valid (throws std::invalid_argument with the reason otherwise).
  EventLogWriter(EventLogWriterOptions options, std::int64_t start_us);
  ~EventLogWriter();
  EventLogWriter(const EventLogWriter&) = delete;
  EventLogWriter& operator=(const EventLogWriter&) = delete;

  // Opens the first file; throws EventLogError naming the path and the errno text.
  void open(std::int64_t now_us);

  // Writes one event (rotating first when due). False when it could not be written; the reason
  // is counted and in last_error().
  // accepted = false: a message the lab's gate refused, written but not counted in the samples'
  // sequence (samples_missing, seq_repeats are the lab's own streams).
  bool write(std::int64_t recv_utime, std::string_view channel, const void* data, std::int32_t size,
             std::int64_t now_us, bool accepted = true);

  // Hands buffered events to the kernel (and fdatasync with sync_on_flush). False on error.
  bool flush(std::int64_t now_us);

  // Time-based work: rotation by time, a new file after a write error. Call often.
  void tick(std::int64_t now_us);

  // Applies retention now (also done by open and tick). Nothing when retention is off.
  void prune(std::int64_t now_us);

  // Writes a status event (state why), flushes, syncs and closes. Nothing is open afterwards.
  void close(std::int64_t now_us, std::string_view why = "stopped");

  // Drops counted before the writer (queue full) and the queue's depth, for the status.
  void add_queue_drops(std::int64_t n) { counters_.queue_drops += n; }
  // Events refused for their size before the writer: counted, and what the last one was said.
  void add_oversize_drops(std::int64_t n, std::int64_t now_us, std::string what);
  void set_queue_depth(double depth) { queue_depth_ = depth; }

  status_t make_status(std::int64_t now_us) const;

  bool is_open() const { return log_ != nullptr; }
  bool disk_full() const { return disk_full_; }  // waiting for space, the file kept open
  bool has_unflushed() const { return unflushed_events_ > 0 || pending_bytes_ > 0; }
  const EventLogCounters& counters() const { return counters_; }
  const std::string& current_path() const { return path_; }
  const std::vector<std::string>& files() const { return files_; }
  const std::vector<std::string>& deleted_files() const { return deleted_; }  // by retention, in order
  const std::string& last_error() const { return last_error_; }
  std::int64_t last_error_utime() const { return last_error_utime_; }
  const EventLogWriterOptions& options() const { return o_; }

 private:
  void open_new_file(std::int64_t now_us);  // throws EventLogError
  void close_file(std::int64_t now_us, std::string_view state);
  void rotate(std::int64_t now_us, std::string_view why);
  bool raw_write(std::int64_t utime, std::string_view channel, const void* data, std::int32_t size,
                 std::int64_t now_us);
  bool fflush_pending(std::int64_t now_us);
  bool sync(std::int64_t now_us);
  void write_status_event(std::int64_t now_us, std::string_view state);
  void fail(std::int64_t now_us, std::string what, int err);
  void fail_text(std::int64_t now_us, std::string text);
  void pause_for_space(std::int64_t now_us, const std::string& what, int err);
  bool cut_back_to_committed();
  void resume_if_due(std::int64_t now_us);
  // Retention on a disk about to fill: with retention on, the oldest of its own files are
  // deleted until `bytes` and a margin fit. False when they still do not.
  bool make_room(std::int64_t bytes, std::int64_t now_us);
  void count_deletions(LogPruneResult& r, std::int64_t now_us);
  void track_samples(std::string_view channel, const void* data, std::int32_t size, std::int64_t recv_utime);
  struct SeqTrack {
    std::int64_t next_seq = 0;    // every sample before it came (or was counted missing)
    ReorderWindow<char> waiting;  // messages past a gap, by sequence number
    bool starting = false;        // first heard past sequence number 0: waiting for what it overtook
  };
  void begin_stream(SeqTrack& t, std::int64_t now_us);
  void release_waiting(SeqTrack& t, std::int64_t now_us);
  bool rotation_due(std::int64_t now_us, std::int64_t next_event_bytes) const;

  EventLogWriterOptions o_;
  std::int64_t start_us_;
  _lcm_eventlog_t* log_ = nullptr;
  std::string path_;
  std::vector<std::string> files_;
  std::vector<char> stdio_buffer_;
  std::int64_t file_open_us_ = 0;
  std::int64_t file_bytes_ = 0;
  std::int64_t file_events_ = 0;        // received events in the current file
  std::int64_t pending_bytes_ = 0;      // written to the FILE* buffer, not yet to the kernel
  std::int64_t unflushed_events_ = 0;   // received events among them
  std::int64_t next_reopen_us_ = 0;
  std::int64_t next_prune_us_ = 0;
  std::time_t last_name_time_ = -1;  // the second of the latest file's name, and its suffix
  int last_suffix_ = 0;
  std::int64_t kept_files_ = 0, kept_bytes_ = 0;  // the logger's files after the last prune
  std::vector<std::string> deleted_;
  // The file as it was after the last successful flush: whole events only.
  std::int64_t committed_bytes_ = 0;
  std::int64_t committed_eventcount_ = 0;
  std::int64_t committed_file_events_ = 0;
  bool disk_full_ = false;
  double queue_depth_ = 0;
  EventLogCounters counters_;
  std::unordered_map<std::string, SeqTrack> next_seq_;  // "bench/session" -> where its samples_t.seq stands
  std::string last_error_;
  std::int64_t last_error_utime_ = 0;
  mutable StatusHeartbeat status_;
};

}  // namespace spindown
