#include "spindown/event_log_writer.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <lcm/eventlog.h>
#include <limits>
#include <stdio_ext.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <spindown/samples_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/message_decode.hpp"

namespace spindown {

namespace {

// magic, event number, timestamp, channel length, data length (lcm eventlog.c).
constexpr std::int64_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;

std::string errno_text(int err) { return std::strerror(err); }

bool is_out_of_space(int err) { return err == ENOSPC || err == EDQUOT; }

std::string instance_name(const EventLogWriterOptions& o) {
  if (!o.instance.empty()) return o.instance;
  return o.bench.empty() ? o.prefix : o.bench;
}

}  // namespace

bool EventLogWriterOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (dir.empty()) return fail("log directory is empty");
  if (prefix.empty() || prefix.find('/') != std::string::npos)
    return fail(fmt::format("file name prefix '{}' must be non-empty and contain no '/'", prefix));
  std::string bench_why;
  if (!bench.empty() && !is_valid_bench_id(bench, &bench_why)) return fail(bench_why);
  if (!std::isfinite(rotate_size_mb) || rotate_size_mb < 0)
    return fail(fmt::format("rotate size {} MB must be >= 0 (0 = never)", rotate_size_mb));
  if (!std::isfinite(rotate_time_s) || rotate_time_s < 0)
    return fail(fmt::format("rotate time {} s must be >= 0 (0 = never)", rotate_time_s));
  if (status_channel.empty()) return fail("status channel is empty");
  if (buffer_bytes < 4096) return fail(fmt::format("buffer of {} bytes is below 4096", buffer_bytes));
  if (!std::isfinite(reopen_interval_s) || reopen_interval_s <= 0)
    return fail(fmt::format("reopen interval {} s must be > 0", reopen_interval_s));
  if (!retention.is_valid(why)) return false;
  if (!std::isfinite(prune_interval_s) || prune_interval_s <= 0)
    return fail(fmt::format("prune interval {} s must be > 0", prune_interval_s));
  return true;
}

std::string event_log_file_name(std::string_view prefix, std::string_view bench, std::time_t unix_time,
                                int suffix) {
  std::tm local{};
  localtime_r(&unix_time, &local);
  char stamp[32] = {};
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d-%H%M%S", &local);
  std::string name = fmt::format("{}-{}", prefix, stamp);
  if (!bench.empty()) name += fmt::format("-{}", bench);
  if (suffix > 0) name += fmt::format(".{}", suffix);
  return name + ".lcm";
}

EventLogWriter::EventLogWriter(EventLogWriterOptions options, std::int64_t start_us)
    : o_(std::move(options)), start_us_(start_us), status_("logger", instance_name(o_), start_us) {
  std::string why;
  if (!o_.is_valid(&why)) throw std::invalid_argument(why);
  stdio_buffer_.resize(o_.buffer_bytes);
}

EventLogWriter::~EventLogWriter() {
  if (log_) close(wall_us(), "stopped");
}

void EventLogWriter::open(std::int64_t now_us) {
  if (!log_) open_new_file(now_us);
}

void EventLogWriter::open_new_file(std::int64_t now_us) {
  const std::time_t t = static_cast<std::time_t>(now_us / 1000000);
  std::string name;
  int suffix_used = 0;
  // O_EXCL: never overwrite a log (a restart or a rotation within the same second). Within a
  // second the suffix only goes up, so a name that retention freed is not taken again and the
  // names keep the order the files were written in.
  for (int suffix = t == last_name_time_ ? last_suffix_ + 1 : 0;; ++suffix) {
    name = o_.dir + "/" + event_log_file_name(o_.prefix, o_.bench, t, suffix);
    const int fd = ::open(name.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      ::close(fd);
      suffix_used = suffix;
      break;
    }
    if (errno != EEXIST || suffix >= 999)
      throw EventLogError(fmt::format("cannot create log file {}: {}", name, errno_text(errno)));
  }
  log_ = lcm_eventlog_create(name.c_str(), "w");
  if (!log_) throw EventLogError(fmt::format("cannot open log file {}: {}", name, errno_text(errno)));
  // Our own buffer, flushed only between events (see raw_write), so the kernel only ever sees
  // whole events and a SIGKILL cannot leave half an event behind.
  std::setvbuf(log_->f, stdio_buffer_.data(), _IOFBF, stdio_buffer_.size());
  last_name_time_ = t;
  last_suffix_ = suffix_used;
  path_ = name;
  files_.push_back(name);
  ++counters_.files;
  file_open_us_ = now_us;
  file_bytes_ = 0;
  file_events_ = 0;
  pending_bytes_ = 0;
  unflushed_events_ = 0;
  committed_bytes_ = 0;
  committed_eventcount_ = 0;
  committed_file_events_ = 0;
  disk_full_ = false;
  write_status_event(now_us, "opened");
  prune(now_us);
}

void EventLogWriter::prune(std::int64_t now_us) {
  if (!o_.retention.enabled()) return;
  next_prune_us_ = now_us + static_cast<std::int64_t>(o_.prune_interval_s * 1e6);
  // The file being written counts with what has reached the kernel; its buffer is small beside
  // any sane budget.
  LogPruneResult r = prune_log_files(o_.dir, o_.prefix, o_.bench, path_, o_.retention);
  count_deletions(r, now_us);
}

void EventLogWriter::count_deletions(LogPruneResult& r, std::int64_t now_us) {
  for (auto& f : r.deleted) deleted_.push_back(std::move(f.path));
  counters_.files_deleted += static_cast<std::int64_t>(r.deleted.size());
  counters_.bytes_deleted += r.bytes_deleted;
  kept_files_ = r.files_kept;
  kept_bytes_ = r.bytes_kept;
  if (!r.errors.empty()) {
    counters_.retention_errors += static_cast<std::int64_t>(r.errors.size());
    last_error_ = r.errors.back();
    last_error_utime_ = now_us;
  }
}

bool EventLogWriter::make_room(std::int64_t bytes, std::int64_t now_us) {
  if (!log_ || !o_.retention.enabled()) return true;
  // The flush, a status event or two, and the filesystem's own rounding.
  const double needed = double(bytes) + 64.0 * 1024;
  const int fd = fileno(log_->f);
  auto enough = [&] {
    struct statvfs fs {};
    return ::fstatvfs(fd, &fs) != 0 || double(fs.f_bavail) * double(fs.f_frsize) >= needed;
  };
  LogPruneResult r = free_log_space(o_.dir, o_.prefix, o_.bench, path_, enough);
  if (r.deleted.empty() && r.errors.empty()) return enough();
  counters_.files_deleted_for_space += static_cast<std::int64_t>(r.deleted.size());
  count_deletions(r, now_us);
  return enough();
}

bool EventLogWriter::rotation_due(std::int64_t now_us, std::int64_t next_event_bytes) const {
  if (!log_ || file_events_ == 0) return false;  // never leave a file with no events
  if (disk_full_) return false;                   // a new file would not fit either
  if (o_.rotate_size_mb > 0 && double(file_bytes_ + next_event_bytes) > o_.rotate_size_mb * 1e6) return true;
  if (o_.rotate_time_s > 0 && double(now_us - file_open_us_) >= o_.rotate_time_s * 1e6) return true;
  return false;
}

bool EventLogWriter::write(std::int64_t recv_utime, std::string_view channel, const void* data,
                           std::int32_t size, std::int64_t now_us, bool accepted) {
  if (accepted) track_samples(channel, data, size, recv_utime);
  resume_if_due(now_us);
  if (disk_full_) {
    ++counters_.events_lost;
    return false;
  }
  if (!log_ && now_us >= next_reopen_us_) {
    try {
      open_new_file(now_us);
    } catch (const EventLogError& e) {
      fail_text(now_us, e.what());
    }
  }
  if (!log_) {
    ++counters_.events_lost;
    return false;
  }
  const std::int64_t event_bytes = kEventHeaderBytes + std::int64_t(channel.size()) + size;
  if (rotation_due(now_us, event_bytes)) {
    rotate(now_us, "rotating");
    if (!log_) {
      ++counters_.events_lost;
      return false;
    }
  }
  if (!raw_write(recv_utime, channel, data, size, now_us)) {
    ++counters_.events_lost;
    return false;
  }
  ++counters_.events;
  ++unflushed_events_;
  ++file_events_;
  return true;
}

bool EventLogWriter::raw_write(std::int64_t utime, std::string_view channel, const void* data,
                               std::int32_t size, std::int64_t now_us) {
  const std::int64_t event_bytes = kEventHeaderBytes + std::int64_t(channel.size()) + size;
  // Hand the buffer to the kernel before it would fill up mid-event.
  if (pending_bytes_ > 0 && pending_bytes_ + event_bytes > std::int64_t(stdio_buffer_.size()))
    if (!fflush_pending(now_us)) return false;
  std::string channel_z(channel);
  lcm_eventlog_event_t ev{};
  ev.timestamp = utime;
  ev.channellen = static_cast<std::int32_t>(channel_z.size());
  ev.datalen = size;
  ev.channel = channel_z.data();
  ev.data = const_cast<void*>(data);
  errno = 0;
  if (lcm_eventlog_write_event(log_, &ev) != 0) {
    fail(now_us, "writing " + path_, errno ? errno : EIO);
    return false;
  }
  pending_bytes_ += event_bytes;
  file_bytes_ += event_bytes;
  counters_.bytes += event_bytes;
  return true;
}

bool EventLogWriter::fflush_pending(std::int64_t now_us) {
  if (!log_) return false;
  if (pending_bytes_ == 0) return true;
  make_room(pending_bytes_, now_us);  // retention frees its old files before an event is lost
  if (std::fflush(log_->f) != 0) {
    fail(now_us, "writing " + path_, errno);
    return false;
  }
  ++counters_.flushes;
  pending_bytes_ = 0;
  unflushed_events_ = 0;
  committed_bytes_ = file_bytes_;
  committed_eventcount_ = log_->eventcount;
  committed_file_events_ = file_events_;
  return true;
}

bool EventLogWriter::sync(std::int64_t now_us) {
  if (!log_) return false;
  if (::fdatasync(fileno(log_->f)) != 0 && errno != EINVAL) {  // EINVAL: a special file
    fail(now_us, "syncing " + path_, errno);
    return false;
  }
  return true;
}

bool EventLogWriter::flush(std::int64_t now_us) {
  const bool had_data = pending_bytes_ > 0;
  if (!fflush_pending(now_us)) return false;
  if (had_data && o_.sync_on_flush) return sync(now_us);
  return true;
}

void EventLogWriter::tick(std::int64_t now_us) {
  for (auto& [key, t] : next_seq_) {
    if (t.starting)
      begin_stream(t, now_us);
    else if (!t.waiting.empty())
      release_waiting(t, now_us);
  }
  if (o_.retention.enabled() && now_us >= next_prune_us_) prune(now_us);
  resume_if_due(now_us);
  if (rotation_due(now_us, 0)) rotate(now_us, "rotating");
}

void EventLogWriter::resume_if_due(std::int64_t now_us) {
  if (!disk_full_ || !log_ || now_us < next_reopen_us_) return;
  make_room(std::int64_t(o_.buffer_bytes), now_us);  // with retention on, its old files make the room
  // Space is back when a buffer's worth is free: the last page of the file may still take a
  // small event while the disk is full, and writing on into it would only fill it again.
  struct statvfs fs {};
  if (::fstatvfs(fileno(log_->f), &fs) == 0 && double(fs.f_bavail) * double(fs.f_frsize) < double(o_.buffer_bytes)) {
    next_reopen_us_ = now_us + static_cast<std::int64_t>(o_.reopen_interval_s * 1e6);
    return;
  }
  // A status event is the probe: when it reaches the kernel, space is back, and the log says
  // so with the counters of what was lost meanwhile. When it does not, pause_for_space cuts it
  // off again and waits another interval (no new error: the same disk is still full).
  const std::int64_t written = counters_.status_events;
  write_status_event(now_us, "resumed");
  if (counters_.status_events == written) return;  // it did not fit in the file's buffer
  if (fflush_pending(now_us))
    disk_full_ = false;
  else
    --counters_.status_events;  // cut off again
}

void EventLogWriter::rotate(std::int64_t now_us, std::string_view why) {
  close_file(now_us, why);
  try {
    open_new_file(now_us);
  } catch (const EventLogError& e) {
    fail_text(now_us, e.what());
  }
}

void EventLogWriter::close_file(std::int64_t now_us, std::string_view state) {
  if (!log_) return;
  write_status_event(now_us, state);
  if (fflush_pending(now_us)) sync(now_us);
  if (log_) {
    lcm_eventlog_destroy(log_);
    log_ = nullptr;
  }
}

void EventLogWriter::close(std::int64_t now_us, std::string_view why) {
  for (auto& [key, t] : next_seq_) {  // the last status counts every gap still open as missing
    if (t.starting) begin_stream(t, std::numeric_limits<std::int64_t>::max());
    if (!t.waiting.empty()) release_waiting(t, std::numeric_limits<std::int64_t>::max());
  }
  close_file(now_us, why);
}

void EventLogWriter::write_status_event(std::int64_t now_us, std::string_view state) {
  if (!log_) return;
  status_t st = make_status(now_us);
  st.state = std::string(state);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(st.getEncodedSize()));
  if (st.encode(buf.data(), 0, static_cast<int>(buf.size())) < 0) return;
  if (raw_write(now_us, o_.status_channel, buf.data(), static_cast<std::int32_t>(buf.size()), now_us))
    ++counters_.status_events;
}

void EventLogWriter::fail(std::int64_t now_us, std::string what, int err) {
  if (log_ && is_out_of_space(err)) {
    pause_for_space(now_us, what, err);
    return;
  }
  fail_text(now_us, fmt::format("{}: {}", what, errno_text(err)));
}

// Drops what did not reach the file (the stdio buffer, and any part of an event the kernel
// took before the disk filled), so the file ends on the last whole event flushed.
bool EventLogWriter::cut_back_to_committed() {
  std::FILE* f = log_->f;
  __fpurge(f);
  std::clearerr(f);
  if (::ftruncate(fileno(f), committed_bytes_) != 0 || ::fseeko(f, committed_bytes_, SEEK_SET) != 0) return false;
  log_->eventcount = committed_eventcount_;
  counters_.bytes -= file_bytes_ - committed_bytes_;
  file_bytes_ = committed_bytes_;
  file_events_ = committed_file_events_;
  return true;
}

void EventLogWriter::pause_for_space(std::int64_t now_us, const std::string& what, int err) {
  const std::int64_t lost = unflushed_events_;
  unflushed_events_ = 0;
  pending_bytes_ = 0;
  if (!cut_back_to_committed()) {
    unflushed_events_ = lost;  // counted as lost by fail_text
    fail_text(now_us, fmt::format("{}: {}; and cutting it back to its last whole event failed: {}", what,
                                  errno_text(err), errno_text(errno)));
    return;
  }
  counters_.events -= lost;  // not in the file: lost, not written
  counters_.events_lost += lost;
  next_reopen_us_ = now_us + static_cast<std::int64_t>(o_.reopen_interval_s * 1e6);
  if (disk_full_) return;  // still full: said once per episode
  disk_full_ = true;
  ++counters_.disk_full_episodes;
  ++counters_.write_errors;
  last_error_ = fmt::format("{}: {}: events are counted as lost until space returns, then written on to the same file",
                            what, errno_text(err));
  last_error_utime_ = now_us;
}

void EventLogWriter::add_oversize_drops(std::int64_t n, std::int64_t now_us, std::string what) {
  if (n <= 0) return;
  counters_.oversize_drops += n;
  last_error_ = std::move(what);
  last_error_utime_ = now_us;
}

void EventLogWriter::fail_text(std::int64_t now_us, std::string text) {
  ++counters_.write_errors;
  last_error_ = std::move(text);
  last_error_utime_ = now_us;
  // Whatever sat in the buffer may not have reached the file.
  counters_.events_lost += unflushed_events_;
  unflushed_events_ = 0;
  pending_bytes_ = 0;
  if (log_) {
    lcm_eventlog_destroy(log_);  // fclose; its own flush attempt fails the same way
    log_ = nullptr;
  }
  next_reopen_us_ = now_us + static_cast<std::int64_t>(o_.reopen_interval_s * 1e6);
}

void EventLogWriter::track_samples(std::string_view channel, const void* data, std::int32_t size,
                                   std::int64_t recv_utime) {
  const auto parsed = parse_channel(channel);
  if (!parsed || parsed->kind != ChannelKind::sample) return;
  samples_t s{};
  if (size <= 0 || !decode_message(s, data, size)) {  // layout checked first: no allocation bombs
    ++counters_.decode_errors;
    return;
  }
  // Per bench and bridge session: a restarted bridge (a new session) numbers from 0 again without
  // being a repeat.
  const std::string key = parsed->bench + "/" + std::to_string(s.source_session);
  const std::int64_t n = std::max<std::int32_t>(s.n, 0);
  auto it = next_seq_.find(key);
  if (it == next_seq_.end()) {
    if (next_seq_.size() >= o_.max_tracked_benches) {
      ++counters_.benches_untracked;
      return;
    }
    SeqTrack& t = next_seq_[key];
    t.next_seq = s.seq + n;
    if (s.seq == 0) return;
    // First heard past its start: it may have overtaken what was sent before it (ReorderWindow::start).
    t.starting = true;
    t.waiting.insert(s.seq, n, recv_utime, char{});
    return;
  }
  SeqTrack& t = it->second;
  const ReorderOptions window;
  if (t.starting) [[unlikely]] {
    if (t.waiting.holds(s.seq, n))
      counters_.seq_repeats += n;
    else
      t.waiting.insert(s.seq, n, recv_utime, char{});
    begin_stream(t, recv_utime);
    return;
  }
  if (s.seq < t.next_seq) {
    if (t.waiting.take_lost(s.seq, n)) {  // it came after all: in the log, so not missing
      counters_.samples_missing -= n;
      counters_.samples_late += n;
    } else {
      counters_.seq_repeats += n;
      // Far behind: an unnamed bridge (session 0) restarted its numbering: follow it.
      if (t.next_seq - s.seq > window.max_samples) {
        release_waiting(t, std::numeric_limits<std::int64_t>::max());
        t.waiting.clear();
        t.next_seq = s.seq + n;
      }
    }
    return;
  }
  if (t.waiting.holds(s.seq, n)) {
    counters_.seq_repeats += n;
    return;
  }
  if (s.seq == t.next_seq)
    t.next_seq += n;
  else
    t.waiting.insert(s.seq, n, recv_utime, char{});
  release_waiting(t, recv_utime);
}

void EventLogWriter::begin_stream(SeqTrack& t, std::int64_t now_us) {
  if (!t.waiting.start(t.next_seq, now_us, ReorderOptions{})) return;
  t.starting = false;
  release_waiting(t, now_us);
}

void EventLogWriter::release_waiting(SeqTrack& t, std::int64_t now_us) {
  t.waiting.release(t.next_seq, now_us, ReorderOptions{}, [&](const ReorderWindow<char>::Entry& e) {
    if (e.seq > t.next_seq) {
      ++counters_.seq_gaps;
      counters_.samples_missing += e.seq - t.next_seq;
    }
    t.next_seq = std::max(t.next_seq, e.seq + e.n);
  });
}

status_t EventLogWriter::make_status(std::int64_t now_us) const {
  status_.set_state(log_ ? (disk_full_ ? "disk full" : "running") : (files_.empty() ? "starting" : "error"));
  const std::pair<const char*, std::int64_t> counters[] = {
      {"events", counters_.events},
      {"bytes", counters_.bytes},
      {"files", counters_.files},
      {"drops", counters_.queue_drops + counters_.events_lost},
      {"write_errors", counters_.write_errors},
      {"flushes", counters_.flushes},
      {"queue_drops", counters_.queue_drops},
      {"oversize_drops", counters_.oversize_drops},
      {"events_lost", counters_.events_lost},
      {"status_events", counters_.status_events},
      {"decode_errors", counters_.decode_errors},
      {"seq_gaps", counters_.seq_gaps},
      {"samples_missing", counters_.samples_missing},
      {"samples_late", counters_.samples_late},
      {"seq_repeats", counters_.seq_repeats},
      {"benches_untracked", counters_.benches_untracked},
      {"disk_full_episodes", counters_.disk_full_episodes},
      {"files_deleted", counters_.files_deleted},
      {"files_deleted_for_space", counters_.files_deleted_for_space},
      {"bytes_deleted", counters_.bytes_deleted},
      {"retention_errors", counters_.retention_errors},
  };
  for (const auto& [name, value] : counters) status_.set_counter(name, value);
  status_.set_gauge("queue_depth", queue_depth_);
  status_.set_gauge("file_bytes", double(file_bytes_));
  status_.set_gauge("unflushed_events", double(unflushed_events_));
  status_.set_gauge("benches_tracked", double(next_seq_.size()));
  if (o_.retention.enabled()) {
    status_.set_gauge("kept_files", double(kept_files_));
    status_.set_gauge("kept_bytes", double(kept_bytes_));
  }
  status_.set_error(last_error_, last_error_utime_);
  return status_.message(now_us);
}

}  // namespace spindown
