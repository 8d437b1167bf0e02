// short_string_equal (core/base/include/spindown/short_string_equal.hpp): the per-message name check of the log
// reader and the fitter core must agree with std::string_view's == for every length and every
// position of a difference, including the overlapping last word.
#include <gtest/gtest.h>

#include <string>

#include "spindown/short_string_equal.hpp"

using spindown::short_string_equal;

TEST(ShortStringEqual, AgreesWithStringViewAtEveryLengthAndPosition) {
  const std::string base = "SPINDOWN.bench-007_lab.SAMPLE.and-some-more-bytes";
  for (std::size_t n = 0; n <= base.size(); ++n) {
    const std::string a = base.substr(0, n);
    std::string b = a;
    EXPECT_TRUE(short_string_equal(a, b)) << n;
    for (std::size_t i = 0; i < n; ++i) {
      b = a;
      b[i] ^= 0x20;
      EXPECT_FALSE(short_string_equal(a, b)) << n << " " << i;
    }
    if (n > 0) {
      EXPECT_FALSE(short_string_equal(a, base.substr(0, n - 1))) << n;
    }
  }
  EXPECT_TRUE(short_string_equal({}, {}));
  EXPECT_FALSE(short_string_equal("SAMPLE", std::string_view("SAMPLE\0", 7)));
}
