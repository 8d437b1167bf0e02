#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "spindown/ordered_parallel.hpp"

using namespace spindown;

// Results arrive in input order even when later inputs finish first.
TEST(OrderedParallel, ConsumesInInputOrder) {
  for (unsigned jobs : {1u, 2u, 4u, 8u}) {
    std::vector<std::size_t> order;
    for_each_ordered(
        100, jobs,
        [](std::size_t i) {
          // Early inputs take longer, so workers finish out of order.
          if (i % 7 == 0) std::this_thread::sleep_for(std::chrono::microseconds(200));
          return i * i;
        },
        [&](std::size_t i, std::size_t r) {
          EXPECT_EQ(r, i * i);
          order.push_back(i);
        });
    ASSERT_EQ(order.size(), 100u) << jobs << " jobs";
    for (std::size_t i = 0; i < order.size(); ++i) EXPECT_EQ(order[i], i);
  }
}

// Several threads really run, and never more than asked.
TEST(OrderedParallel, UsesUpToJobsThreads) {
  std::mutex mu;
  std::set<std::thread::id> ids;
  std::atomic<int> running{0}, most{0};
  for_each_ordered(
      64, 3,
      [&](std::size_t i) {
        const int now = ++running;
        int seen = most.load();
        while (now > seen && !most.compare_exchange_weak(seen, now)) {
        }
        {
          std::lock_guard lock(mu);
          ids.insert(std::this_thread::get_id());
        }
        std::this_thread::sleep_for(std::chrono::microseconds(300));
        --running;
        return i;
      },
      [](std::size_t, std::size_t) {});
  EXPECT_LE(most.load(), 3);
  EXPECT_GE(ids.size(), 2u);
  EXPECT_FALSE(ids.count(std::this_thread::get_id()));
}

// A failing input stops the work and its exception reaches the caller; results before it
// were consumed.
TEST(OrderedParallel, PropagatesAnException) {
  std::vector<std::size_t> seen;
  EXPECT_THROW(for_each_ordered(
                   50, 4,
                   [](std::size_t i) {
                     if (i == 20) throw std::runtime_error("input 20 is bad");
                     return i;
                   },
                   [&](std::size_t i, std::size_t) { seen.push_back(i); }),
               std::runtime_error);
  EXPECT_LE(seen.size(), 20u);
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i);
}

TEST(OrderedParallel, NothingToDo) {
  int calls = 0;
  for_each_ordered(0, 4, [&](std::size_t) { return ++calls; }, [&](std::size_t, int) { ++calls; });
  EXPECT_EQ(calls, 0);
}

// The consumer sleeps until a batch of results in a row is ready: every count of inputs, batch
// boundary or not, and the last, partial batch, still comes out whole and in order, with uneven
// work and a slow consumer; an exception near the end still reaches the caller.
TEST(OrderedParallel, BatchedHandoffsLoseNothing) {
  for (unsigned jobs : {2u, 3u, 5u}) {
    for (std::size_t n = 2; n <= 41; n += 3) {
      std::vector<std::size_t> order;
      for_each_ordered(
          n, jobs,
          [](std::size_t i) {
            if (i % 5 == 1) std::this_thread::sleep_for(std::chrono::microseconds(100));
            return i + 1;
          },
          [&](std::size_t i, std::size_t r) {
            EXPECT_EQ(r, i + 1);
            if (i % 11 == 3) std::this_thread::sleep_for(std::chrono::microseconds(300));
            order.push_back(i);
          });
      ASSERT_EQ(order.size(), n) << jobs << " jobs";
      for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(order[i], i);
    }
    std::vector<std::size_t> seen;
    EXPECT_THROW(for_each_ordered(
                     30, jobs,
                     [](std::size_t i) {
                       if (i == 29) throw std::runtime_error("the last input is bad");
                       return i;
                     },
                     [&](std::size_t i, std::size_t) { seen.push_back(i); }),
                 std::runtime_error);
    for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], i);
  }
}
