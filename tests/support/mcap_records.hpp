#pragma once
// Reading back an MCAP file in a test, independently of McapWriter: the records of a byte
// range, and little-endian fields at an offset (spec "Serialization").
#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace spindown::testing {

inline std::uint64_t le(std::string_view b, std::size_t at, int bytes) {
  EXPECT_LE(at + bytes, b.size()) << "field past the end";
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(b[at + i]);
  return v;
}

struct McapRecord {
  std::uint8_t op = 0;
  std::size_t offset = 0;   // of the opcode
  std::string_view body;    // the record's content
  std::size_t size() const { return 9 + body.size(); }
};

// The records of bytes [from, to); a record that runs past `to` fails the test.
inline std::vector<McapRecord> mcap_records(std::string_view b, std::size_t from, std::size_t to) {
  std::vector<McapRecord> out;
  std::size_t at = from;
  while (at < to) {
    if (at + 9 > to) {
      ADD_FAILURE() << "record header past the end at " << at;
      break;
    }
    const std::uint64_t len = le(b, at + 1, 8);
    if (at + 9 + len > to) {
      ADD_FAILURE() << "record at " << at << " runs past the end";
      break;
    }
    out.push_back({static_cast<std::uint8_t>(b[at]), at, b.substr(at + 9, len)});
    at += 9 + len;
  }
  return out;
}

// A uint32-length-prefixed string at body[*at]; advances *at.
inline std::string_view mcap_string(std::string_view body, std::size_t* at) {
  const auto n = le(body, *at, 4);
  const std::string_view s = body.substr(*at + 4, n);
  *at += 4 + n;
  return s;
}

}  // namespace spindown::testing
