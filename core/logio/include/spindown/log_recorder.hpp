#pragma once
// spindown-logger's two halves: the LCM thread only copies each received event into a bounded
// queue (offer), and a writer thread drains the queue into an EventLogWriter and flushes it on
// a timer even when no event arrives, so a slow disk never stalls the socket and a killed
// logger loses at most one flush interval. stop() drains everything queued before closing.
//
// Events beyond the queue's capacity are dropped and counted (never silently): they show in
// the writer's status as queue_drops/drops.
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include <spindown/status_t.hpp>

#include "spindown/event_log_writer.hpp"
#include "spindown/message_queue.hpp"

namespace spindown {

struct LogRecorderOptions {
  std::size_t queue_capacity = 10000;        // events waiting for the writer, at most
  std::size_t queue_max_bytes = 256u << 20;  // and their payload bytes, at most
  // A larger message is not recorded (counted, named in the status): LCM 1.3.1 assembles what a
  // single datagram's fragment header claims (up to 256 MB), so one 1 KB datagram could
  // otherwise put 100 MB of zeros into the log. spindown's messages are at most a few kB.
  std::size_t max_event_bytes = 8u << 20;
  double flush_interval_s = 0.5;             // buffered events reach the kernel at least this often
  double status_interval_s = 0.1;            // how often status() is refreshed by the writer thread

  bool is_valid(std::string* why) const;
};

class LogRecorder {
 public:
  // writer must be open and must outlive the recorder; the recorder's thread owns it until stop().
  LogRecorder(EventLogWriter& writer, LogRecorderOptions options);
  ~LogRecorder();  // stop() if still running
  LogRecorder(const LogRecorder&) = delete;
  LogRecorder& operator=(const LogRecorder&) = delete;

  void start();

  // From the receiving thread: queue one event. False when the queue was full (counted).
  // accepted: the lab's gate let it through; a refused one is recorded all the same (the log is
  // the evidence) but never counted in the samples' sequence (a forger's gaps are not loss).
  bool offer(std::int64_t recv_utime, std::string_view channel, const void* data, std::int32_t size,
             bool accepted = true);

  // Writes everything queued, closes the writer with state why and joins the thread.
  void stop(std::string_view why = "stopped");

  // The writer's latest status (refreshed by the writer thread), with utime set to now_us.
  status_t status(std::int64_t now_us) const;

  // Monotonic time (monotonic_ns) of the writer thread's latest round: it comes round at least
  // every flush interval, so an old value means it is stuck (a hung disk), for the watchdog.
  std::int64_t writer_alive_ns() const { return writer_alive_ns_.load(std::memory_order_relaxed); }

  std::size_t queue_depth() const { return queue_.depth(); }
  std::int64_t dropped() const { return queue_.counts().full_drops; }

 private:
  void run();
  void refresh_status(std::int64_t now_us);

  EventLogWriter& writer_;
  LogRecorderOptions o_;
  MessageQueue queue_;
  std::mutex stop_mutex_;
  bool stopping_ = false;                              // under stop_mutex_
  std::string stop_why_ = "stopped";                   // under stop_mutex_
  std::int64_t dropped_reported_ = 0, oversize_reported_ = 0;  // writer thread

  mutable std::mutex status_mutex_;
  status_t status_{};
  std::int64_t next_status_us_ = 0;

  std::atomic<std::int64_t> writer_alive_ns_{0};
  std::thread thread_;
};

}  // namespace spindown
