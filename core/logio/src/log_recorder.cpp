#include "spindown/log_recorder.hpp"

#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace spindown {

namespace {
std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}
}  // namespace

bool LogRecorderOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (queue_capacity < 1) return fail("queue capacity must be at least 1 event");
  if (queue_max_bytes < 1024) return fail(fmt::format("queue byte limit {} is below 1024", queue_max_bytes));
  if (max_event_bytes < 1024) return fail(fmt::format("largest event {} bytes is below 1024", max_event_bytes));
  if (!std::isfinite(flush_interval_s) || flush_interval_s <= 0 || flush_interval_s > 3600)
    return fail(fmt::format("flush interval {} s must be in (0, 3600]", flush_interval_s));
  if (!std::isfinite(status_interval_s) || status_interval_s <= 0)
    return fail(fmt::format("status interval {} s must be > 0", status_interval_s));
  return true;
}

LogRecorder::LogRecorder(EventLogWriter& writer, LogRecorderOptions options) : writer_(writer), o_(options) {
  std::string why;
  if (!o_.is_valid(&why)) throw std::invalid_argument(why);
  status_ = writer_.make_status(wall_us());
}

LogRecorder::~LogRecorder() { stop(); }

void LogRecorder::start() {
  if (thread_.joinable()) return;
  thread_ = std::thread([this] { run(); });
}

bool LogRecorder::offer(std::int64_t recv_utime, std::string_view channel, const void* data,
                        std::int32_t size) {
  const std::size_t n = size > 0 ? static_cast<std::size_t>(size) : 0;
  if (n > o_.max_event_bytes) {
    std::lock_guard lock(queue_mutex_);
    ++oversize_;
    last_oversize_ = fmt::format("message of {} bytes on {} not recorded: larger than the largest event kept ({} "
                                 "bytes; a fragment header claiming more than was sent?)",
                                 n, channel.substr(0, 80), o_.max_event_bytes);
    return false;
  }
  Event ev{recv_utime, std::string(channel), {}};
  ev.data.assign(static_cast<const std::uint8_t*>(data), static_cast<const std::uint8_t*>(data) + n);
  bool was_empty = false;
  {
    std::lock_guard lock(queue_mutex_);
    if (queue_.size() >= o_.queue_capacity || queue_bytes_ + n > o_.queue_max_bytes) {
      dropped_.fetch_add(1);
      return false;
    }
    was_empty = queue_.empty();
    queue_bytes_ += n;
    queue_.push_back(std::move(ev));
  }
  if (was_empty) wake_.notify_one();
  return true;
}

std::size_t LogRecorder::queue_depth() const {
  std::lock_guard lock(queue_mutex_);
  return queue_.size();
}

void LogRecorder::stop(std::string_view why) {
  {
    std::lock_guard lock(queue_mutex_);
    if (stopping_ && !thread_.joinable()) return;
    stopping_ = true;
    stop_why_ = std::string(why);
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

status_t LogRecorder::status(std::int64_t now_us) const {
  std::lock_guard lock(status_mutex_);
  status_t st = status_;
  st.uptime_s += double(now_us - st.utime) * 1e-6;
  st.utime = now_us;
  return st;
}

void LogRecorder::refresh_status(std::int64_t now_us) {
  const std::int64_t dropped = dropped_.load();
  writer_.add_queue_drops(dropped - dropped_reported_);
  dropped_reported_ = dropped;
  {
    std::string what;
    std::int64_t oversize = 0;
    {
      std::lock_guard lock(queue_mutex_);
      oversize = oversize_;
      what = last_oversize_;
    }
    writer_.add_oversize_drops(oversize - oversize_reported_, now_us, std::move(what));
    oversize_reported_ = oversize;
  }
  writer_.set_queue_depth(double(queue_depth()));
  status_t st = writer_.make_status(now_us);
  std::lock_guard lock(status_mutex_);
  status_ = std::move(st);
}

void LogRecorder::run() {
  using clock = std::chrono::steady_clock;
  const auto flush_every = std::chrono::microseconds(static_cast<std::int64_t>(o_.flush_interval_s * 1e6));
  auto next_flush = clock::now() + flush_every;
  std::deque<Event> batch;
  for (;;) {
    bool stopping = false;
    {
      std::unique_lock lock(queue_mutex_);
      wake_.wait_until(lock, next_flush, [&] { return !queue_.empty() || stopping_; });
      batch.swap(queue_);
      queue_bytes_ = 0;
      stopping = stopping_;
    }
    for (const Event& ev : batch)
      writer_.write(ev.utime, ev.channel, ev.data.data(), static_cast<std::int32_t>(ev.data.size()), wall_us());
    batch.clear();

    const std::int64_t now = wall_us();
    // The timer flush: events that arrived since the last one reach the kernel even when no
    // further message comes (lcm-logger 1.3.1 waits for the next message).
    if (clock::now() >= next_flush) {
      writer_.flush(now);
      next_flush = clock::now() + flush_every;
    }
    writer_.tick(now);
    if (stopping) {
      std::unique_lock lock(queue_mutex_);
      if (queue_.empty()) break;  // else: events offered during the last batch, write them too
      continue;
    }
    if (now >= next_status_us_) {
      refresh_status(now);
      next_status_us_ = now + static_cast<std::int64_t>(o_.status_interval_s * 1e6);
    }
  }
  const std::int64_t now = wall_us();
  refresh_status(now);  // counts the last drops into the closing status event
  std::string why;
  {
    std::lock_guard lock(queue_mutex_);
    why = stop_why_;
  }
  writer_.close(now, why);
  refresh_status(wall_us());
}

}  // namespace spindown
