#include "spindown/message_queue.hpp"

#include <algorithm>

#include "spindown/clock.hpp"

namespace spindown {

MessageQueue::Offer MessageQueue::offer(std::int64_t recv_utime, std::string_view channel, const void* data,
                                        std::size_t size, bool accepted) {
  if (size > limits_.max_message_bytes) {
    std::lock_guard lock(mutex_);
    ++counts_.oversize_drops;
    counts_.last_oversize_bytes = size;
    counts_.last_oversize_channel = std::string(channel);
    return Offer::oversize;
  }
  QueuedMessage m{recv_utime, steady_wall_us(), accepted, std::string(channel), {}};
  const auto* bytes = static_cast<const unsigned char*>(data);
  if (size > 0) m.data.assign(bytes, bytes + size);
  bool was_empty = false;
  {
    std::lock_guard lock(mutex_);
    if (closed_ || queue_.size() >= limits_.max_messages || bytes_ + size > limits_.max_bytes) {
      ++counts_.full_drops;
      return Offer::full;
    }
    was_empty = queue_.empty();
    bytes_ += size;
    queue_.push_back(std::move(m));
    counts_.high_water = std::max(counts_.high_water, queue_.size());
  }
  // The worker waits only on an empty queue.
  if (was_empty) wake_.notify_one();
  return Offer::queued;
}

bool MessageQueue::take_all(std::deque<QueuedMessage>& batch, std::chrono::steady_clock::time_point until) {
  batch.clear();
  std::unique_lock lock(mutex_);
  wake_.wait_until(lock, until, [&] { return closed_ || !queue_.empty(); });
  batch.swap(queue_);
  bytes_ = 0;
  return !closed_;
}

void MessageQueue::close() {
  {
    std::lock_guard lock(mutex_);
    closed_ = true;
  }
  wake_.notify_all();
}

MessageQueueCounts MessageQueue::counts() const {
  std::lock_guard lock(mutex_);
  MessageQueueCounts c = counts_;
  c.depth = queue_.size();
  return c;
}

std::size_t MessageQueue::depth() const {
  std::lock_guard lock(mutex_);
  return queue_.size();
}

}  // namespace spindown
