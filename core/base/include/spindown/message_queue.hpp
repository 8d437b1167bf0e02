#pragma once
// Received messages on their way from the receiving thread to a worker (the fitter's core, the
// logger's writer), so a slow fit or a slow disk never stalls reception. Bounded in messages and
// in bytes; whatever it refuses is counted, never dropped in silence:
//   full      — the queue holds max_messages, or the message would pass max_bytes;
//   oversize  — one message larger than max_message_bytes (LCM 1.3.1 assembles whatever size a
//               fragment header claims, up to 256 MB: one forged 1 kB datagram becomes a 100 MB
//               message of zeros), named by its size and channel.
// offer() copies the bytes (outside the lock) and never blocks on the worker; take_all() hands
// the worker everything queued at once. After close() nothing more is queued, and the take that
// finds the queue closed is the last.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace spindown {

struct QueuedMessage {
  std::int64_t recv_utime = 0;  // wall time LCM read it (a signature's freshness is judged on it)
  std::int64_t host_utime = 0;  // steady_wall_us() when queued: for durations (clock.hpp)
  bool accepted = true;         // the receiver's gate let it through (the logger records every message)
  std::string channel;
  std::vector<unsigned char> data;
};

struct MessageQueueLimits {
  std::size_t max_messages = 10000;
  std::size_t max_bytes = 256u << 20;          // payload bytes queued at once
  std::size_t max_message_bytes = 256u << 20;  // one message; larger ones are oversize
};

struct MessageQueueCounts {
  std::size_t depth = 0;                 // messages queued now
  std::size_t high_water = 0;            // the most queued at once
  std::int64_t full_drops = 0;           // refused: queue full (or closed)
  std::int64_t oversize_drops = 0;       // refused: larger than max_message_bytes
  std::size_t last_oversize_bytes = 0;   // the last of them
  std::string last_oversize_channel;
};

class MessageQueue {
 public:
  enum class Offer { queued, full, oversize };

  explicit MessageQueue(MessageQueueLimits limits) : limits_(limits) {}
  MessageQueue(const MessageQueue&) = delete;
  MessageQueue& operator=(const MessageQueue&) = delete;

  // From the receiving thread.
  Offer offer(std::int64_t recv_utime, std::string_view channel, const void* data, std::size_t size,
              bool accepted = true);

  // From the worker: waits until a message is queued, close() or until, then moves everything
  // queued into batch (emptied first). False once the queue is closed: this batch is the last.
  bool take_all(std::deque<QueuedMessage>& batch, std::chrono::steady_clock::time_point until);

  // No more offers; wakes the worker.
  void close();

  MessageQueueCounts counts() const;
  std::size_t depth() const;
  const MessageQueueLimits& limits() const { return limits_; }

 private:
  const MessageQueueLimits limits_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<QueuedMessage> queue_;
  std::size_t bytes_ = 0;
  bool closed_ = false;
  MessageQueueCounts counts_;
};

}  // namespace spindown
