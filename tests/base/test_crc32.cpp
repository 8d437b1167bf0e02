// CRC-32 as zlib and MCAP compute it: the standard check value, the empty input, and the same
// result in pieces as in one go.
#include <gtest/gtest.h>

#include <string>

#include "spindown/crc32.hpp"

namespace spindown {
namespace {

TEST(Crc32, CheckValues) {
  EXPECT_EQ(crc32("123456789"), 0xCBF43926u);  // the catalogue's check value for CRC-32/ISO-HDLC
  EXPECT_EQ(crc32(""), 0u);
  EXPECT_EQ(crc32("The quick brown fox jumps over the lazy dog"), 0x414FA339u);
}

TEST(Crc32, IncrementalEqualsWhole) {
  std::string s;
  for (int i = 0; i < 1000; ++i) s.push_back(static_cast<char>(i * 7919));
  std::uint32_t c = 0;
  for (std::size_t at = 0; at < s.size(); at += 37) c = crc32_update(c, s.data() + at, std::min<std::size_t>(37, s.size() - at));
  EXPECT_EQ(c, crc32(s));
}

}  // namespace
}  // namespace spindown
