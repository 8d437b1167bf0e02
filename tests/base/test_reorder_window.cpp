// A numbered stream put back in order (reorder_window.hpp): a gap is lost only when a message past
// it has waited the window, timed from the earliest message still waiting.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "spindown/reorder_window.hpp"

namespace spindown {
namespace {

constexpr std::int64_t s = 1'000'000;

TEST(ReorderWindow, AGapIsTimedFromTheEarliestMessageStillWaiting) {
  ReorderWindow<int> w;
  const ReorderOptions o;  // 2 s
  std::int64_t next = 0;
  std::vector<std::int64_t> taken;
  const auto take = [&](const ReorderWindow<int>::Entry& e) {
    taken.push_back(e.seq);
    next = e.seq + e.n;
  };
  w.insert(2, 1, 0, 0);         // 0, 1 missing; came at 0 s
  w.insert(4, 1, 19 * s / 10, 0);  // 3 missing; came at 1.9 s
  w.release(next, s, o, take);
  EXPECT_TRUE(taken.empty()) << "the gap may still fill";
  w.release(next, 2 * s, o, take);  // 0, 1 lost (waited 2 s); 3's gap has waited 0.1 s only
  EXPECT_EQ(taken, std::vector<std::int64_t>{2});
  EXPECT_FALSE(w.empty());
  EXPECT_TRUE(w.take_lost(0, 2).has_value()) << "a sample of a lost gap that comes after is late";
  w.release(next, 39 * s / 10, o, take);
  EXPECT_EQ(taken, (std::vector<std::int64_t>{2, 4}));
  EXPECT_TRUE(w.empty());
}

TEST(ReorderWindow, AFilledGapReleasesWhatWaitedAtOnceAndACopyIsHeld) {
  ReorderWindow<int> w;
  std::int64_t next = 0;
  std::vector<std::int64_t> taken;
  const auto take = [&](const ReorderWindow<int>::Entry& e) {
    taken.push_back(e.seq);
    next = e.seq + e.n;
  };
  w.insert(1, 2, 0, 0);
  w.insert(3, 1, 0, 0);
  EXPECT_TRUE(w.holds(2, 1));
  EXPECT_FALSE(w.holds(4, 1));
  next = 1;  // 0 came
  w.release(next, 0, {}, take);
  EXPECT_EQ(taken, (std::vector<std::int64_t>{1, 3}));
  EXPECT_FALSE(w.take_lost(0, 1).has_value()) << "nothing was lost";
}

}  // namespace
}  // namespace spindown
