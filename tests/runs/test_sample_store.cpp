// The run detector's sample store: every sample stays at its absolute index as the ring grows and
// as old samples are forgotten, and a store that forgets keeps its size.
#include <gtest/gtest.h>

#include <cstddef>

#include "spindown/sample_store.hpp"

using namespace spindown;

TEST(SampleStore, EverySampleStaysAtItsIndexAsTheRingGrows) {
  SampleStore s;
  const std::size_t n = 5 * SampleStore::initial_size + 17;
  for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(s.push({0.02 * double(i), 3.0 - 1e-3 * double(i)}), i);
  EXPECT_EQ(s.base(), 0u);
  EXPECT_EQ(s.end(), n);
  EXPECT_GE(s.capacity(), n);
  for (std::size_t i = 0; i < n; ++i) {
    ASSERT_DOUBLE_EQ(s.t(i), 0.02 * double(i)) << i;
    ASSERT_DOUBLE_EQ(s.v(i), 3.0 - 1e-3 * double(i)) << i;
  }
}

TEST(SampleStore, ForgettingOldSamplesKeepsTheRingItsSizeAndTheRestInPlace) {
  SampleStore s;
  for (std::size_t i = 0; i < 100000; ++i) {
    s.push({double(i), double(i % 7)});
    if (s.size() > 1000) s.drop_before(s.end() - 1000);
  }
  EXPECT_EQ(s.capacity(), SampleStore::initial_size);
  EXPECT_EQ(s.size(), 1000u);
  for (std::size_t i = s.base(); i < s.end(); ++i) ASSERT_EQ(s.v(i), double(i % 7)) << i;
  s.drop_before(s.end() + 50);  // never past the end
  EXPECT_EQ(s.base(), s.end());
  EXPECT_EQ(s.size(), 0u);
}

TEST(SampleStore, ALoopWritingThroughTheRawViewThenSetEndIsAPush) {
  SampleStore s;
  s.push({0.0, 1.0});
  SampleStore::Sample* ring = s.data();
  for (std::size_t i = 1; i < 10; ++i) ring[i & s.mask()] = {double(i), 1.0 + double(i)};
  s.set_end(10);
  ASSERT_EQ(s.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) EXPECT_EQ(s.v(i), 1.0 + double(i));
}
