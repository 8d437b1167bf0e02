// The bounded queue between a receiving thread and a worker (the fitter's and the logger's):
// everything it refuses is counted, what it takes is handed over whole and in order, and close()
// makes the next take the last.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "spindown/message_queue.hpp"

namespace spindown {
namespace {

using namespace std::chrono_literals;

std::chrono::steady_clock::time_point soon() { return std::chrono::steady_clock::now() + 10ms; }

TEST(MessageQueue, HandsOverEverythingInOrder) {
  MessageQueue q({.max_messages = 10, .max_bytes = 1000, .max_message_bytes = 100});
  EXPECT_EQ(q.offer(1, "A", "ab", 2), MessageQueue::Offer::queued);
  EXPECT_EQ(q.offer(2, "B", "cde", 3), MessageQueue::Offer::queued);
  std::deque<QueuedMessage> batch;
  EXPECT_TRUE(q.take_all(batch, soon()));
  ASSERT_EQ(batch.size(), 2u);
  EXPECT_EQ(batch[0].recv_utime, 1);
  EXPECT_EQ(batch[0].channel, "A");
  EXPECT_EQ(std::string(batch[1].data.begin(), batch[1].data.end()), "cde");
  EXPECT_EQ(q.depth(), 0u);
  EXPECT_TRUE(q.take_all(batch, soon()));  // nothing: waits until the deadline
  EXPECT_TRUE(batch.empty());
}

TEST(MessageQueue, FullByCountOrBytesIsCounted) {
  MessageQueue q({.max_messages = 2, .max_bytes = 10, .max_message_bytes = 10});
  EXPECT_EQ(q.offer(1, "A", "1234", 4), MessageQueue::Offer::queued);
  EXPECT_EQ(q.offer(2, "A", "1234567", 7), MessageQueue::Offer::full);  // 11 bytes
  EXPECT_EQ(q.offer(3, "A", "1234", 4), MessageQueue::Offer::queued);
  EXPECT_EQ(q.offer(4, "A", "1", 1), MessageQueue::Offer::full);  // 3 messages
  const auto c = q.counts();
  EXPECT_EQ(c.full_drops, 2);
  EXPECT_EQ(c.depth, 2u);
  EXPECT_EQ(c.high_water, 2u);
  EXPECT_EQ(c.oversize_drops, 0);
}

TEST(MessageQueue, AnOversizeMessageIsNamedAndTheRestKept) {
  MessageQueue q({.max_messages = 10, .max_bytes = 1000, .max_message_bytes = 4});
  const std::vector<unsigned char> big(5, 0);
  EXPECT_EQ(q.offer(1, "SPINDOWN.x.SAMPLE", big.data(), big.size()), MessageQueue::Offer::oversize);
  EXPECT_EQ(q.offer(2, "SPINDOWN.x.SAMPLE", "abcd", 4), MessageQueue::Offer::queued);
  const auto c = q.counts();
  EXPECT_EQ(c.oversize_drops, 1);
  EXPECT_EQ(c.last_oversize_bytes, 5u);
  EXPECT_EQ(c.last_oversize_channel, "SPINDOWN.x.SAMPLE");
  EXPECT_EQ(c.full_drops, 0);
  EXPECT_EQ(c.depth, 1u);
}

TEST(MessageQueue, AnOfferWakesAWaitingWorker) {
  MessageQueue q({});
  std::thread producer([&] {
    std::this_thread::sleep_for(20ms);
    q.offer(7, "A", "x", 1);
  });
  std::deque<QueuedMessage> batch;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < 100 && batch.empty(); ++i) q.take_all(batch, std::chrono::steady_clock::now() + 10s);
  producer.join();
  ASSERT_EQ(batch.size(), 1u);
  EXPECT_LT(std::chrono::steady_clock::now() - start, 5s);
}

TEST(MessageQueue, CloseMakesTheNextTakeTheLastAndRefusesMore) {
  MessageQueue q({});
  q.offer(1, "A", "x", 1);
  q.close();
  EXPECT_EQ(q.offer(2, "A", "y", 1), MessageQueue::Offer::full);
  std::deque<QueuedMessage> batch;
  EXPECT_FALSE(q.take_all(batch, std::chrono::steady_clock::now() + 10s));  // at once: closed
  ASSERT_EQ(batch.size(), 1u);
  EXPECT_EQ(q.counts().full_drops, 1);
}

TEST(MessageQueue, NothingLostBetweenTwoThreads) {
  MessageQueue q({.max_messages = 1'000'000, .max_bytes = 1u << 30, .max_message_bytes = 64});
  constexpr int n = 20000;
  std::thread producer([&] {
    for (int i = 0; i < n; ++i) q.offer(i, "A", &i, sizeof i);
    q.close();
  });
  std::deque<QueuedMessage> batch;
  std::int64_t next = 0;
  bool open = true;
  while (open) {
    open = q.take_all(batch, std::chrono::steady_clock::now() + 1s);
    for (const auto& m : batch) ASSERT_EQ(m.recv_utime, next++);
  }
  producer.join();
  EXPECT_EQ(next, n);
}

}  // namespace
}  // namespace spindown
