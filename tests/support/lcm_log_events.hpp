#pragma once
// Writing an LCM event log in a test, event by event, as lcm-logger writes it.
#include <gtest/gtest.h>

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

namespace spindown::testing {

// Appends message m on channel at utime; a failed write fails the test.
template <class M>
void write_event(lcm::LogFile& log, const std::string& channel, const M& m, std::int64_t utime) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent e{0, utime, channel, static_cast<std::int32_t>(buf.size()), buf.data()};
  ASSERT_EQ(log.writeEvent(&e), 0);
}

}  // namespace spindown::testing
