#include "spindown/log_recorder.hpp"

#include <chrono>
#include <cmath>
#include <deque>
#include <fmt/format.h>
#include <stdexcept>

#include "spindown/clock.hpp"

namespace spindown {

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

namespace {
// Checked before the queue is made of them.
const LogRecorderOptions& valid(const LogRecorderOptions& o) {
  std::string why;
  if (!o.is_valid(&why)) throw std::invalid_argument(why);
  return o;
}
}  // namespace

LogRecorder::LogRecorder(EventLogWriter& writer, LogRecorderOptions options)
    : writer_(writer),
      o_(valid(options)),
      queue_({.max_messages = o_.queue_capacity, .max_bytes = o_.queue_max_bytes, .max_message_bytes = o_.max_event_bytes}) {
  status_ = writer_.make_status(wall_us());
}

LogRecorder::~LogRecorder() { stop(); }

void LogRecorder::start() {
  if (thread_.joinable()) return;
  writer_alive_ns_.store(monotonic_ns());
  thread_ = std::thread([this] { run(); });
}

bool LogRecorder::offer(std::int64_t recv_utime, std::string_view channel, const void* data,
                        std::int32_t size, bool accepted) {
  const std::size_t n = size > 0 ? static_cast<std::size_t>(size) : 0;
  return queue_.offer(recv_utime, channel, data, n, accepted) == MessageQueue::Offer::queued;
}

void LogRecorder::stop(std::string_view why) {
  {
    std::lock_guard lock(stop_mutex_);
    if (stopping_ && !thread_.joinable()) return;
    stopping_ = true;
    stop_why_ = std::string(why);
  }
  queue_.close();
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
  const MessageQueueCounts q = queue_.counts();
  writer_.add_queue_drops(q.full_drops - dropped_reported_);
  dropped_reported_ = q.full_drops;
  if (q.oversize_drops > oversize_reported_)
    writer_.add_oversize_drops(q.oversize_drops - oversize_reported_, now_us,
                               fmt::format("message of {} bytes on {} not recorded: larger than the largest event "
                                           "kept ({} bytes; a fragment header claiming more than was sent?)",
                                           q.last_oversize_bytes, q.last_oversize_channel.substr(0, 80),
                                           o_.max_event_bytes));
  oversize_reported_ = q.oversize_drops;
  writer_.set_queue_depth(double(q.depth));
  status_t st = writer_.make_status(now_us);
  std::lock_guard lock(status_mutex_);
  status_ = std::move(st);
}

void LogRecorder::run() {
  using clock = std::chrono::steady_clock;
  const auto flush_every = std::chrono::microseconds(static_cast<std::int64_t>(o_.flush_interval_s * 1e6));
  auto next_flush = clock::now() + flush_every;
  std::deque<QueuedMessage> batch;
  for (;;) {
    writer_alive_ns_.store(monotonic_ns(), std::memory_order_relaxed);
    // After stop() the queue is closed: this batch holds everything offered, and is the last.
    const bool open = queue_.take_all(batch, next_flush);
    for (const QueuedMessage& ev : batch)
      writer_.write(ev.recv_utime, ev.channel, ev.data.data(), static_cast<std::int32_t>(ev.data.size()), wall_us(),
                    ev.accepted);
    batch.clear();

    const std::int64_t now = wall_us();
    // The timer flush: events that arrived since the last one reach the kernel even when no
    // further message comes (lcm-logger 1.3.1 waits for the next message).
    if (clock::now() >= next_flush) {
      writer_.flush(now);
      next_flush = clock::now() + flush_every;
    }
    writer_.tick(now);
    if (!open) break;
    if (now >= next_status_us_) {
      refresh_status(now);
      next_status_us_ = now + static_cast<std::int64_t>(o_.status_interval_s * 1e6);
    }
  }
  const std::int64_t now = wall_us();
  refresh_status(now);  // counts the last drops into the closing status event
  std::string why;
  {
    std::lock_guard lock(stop_mutex_);
    why = stop_why_;
  }
  writer_.close(now, why);
  refresh_status(wall_us());
}

}  // namespace spindown
