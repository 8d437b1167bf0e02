#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "spindown/line_splitter.hpp"

using spindown::LineSplitter;

namespace {
struct Collected {
  std::vector<std::string> lines;
  std::vector<bool> oversize;
  LineSplitter::Handler handler() {
    return [this](const LineSplitter::Line& l) {
      lines.emplace_back(l.text);
      oversize.push_back(l.oversize);
    };
  }
};
}  // namespace

TEST(LineSplitter, SplitsAcrossChunksAndStripsCrLf) {
  LineSplitter s(64);
  Collected c;
  const auto h = c.handler();
  s.feed("5234\t0.0", h);
  s.feed("0\r\n5254\t0.01\r", h);
  s.feed("\n\n52", h);
  ASSERT_EQ(c.lines.size(), 3u);
  EXPECT_EQ(c.lines[0], "5234\t0.00");
  EXPECT_EQ(c.lines[1], "5254\t0.01");
  EXPECT_EQ(c.lines[2], "");
  EXPECT_EQ(s.buffered(), 2u);
  EXPECT_EQ(s.lines(), 3u);
  EXPECT_EQ(s.oversize_lines(), 0u);
}

TEST(LineSplitter, LineOfExactlyTheLimitPasses) {
  LineSplitter s(8);
  Collected c;
  s.feed("12345678\n", c.handler());
  ASSERT_EQ(c.lines.size(), 1u);
  EXPECT_EQ(c.lines[0], "12345678");
  EXPECT_FALSE(c.oversize[0]);
}

TEST(LineSplitter, OverlongLineIsReportedOnceAndDiscardedToItsNewline) {
  LineSplitter s(8);
  Collected c;
  const auto h = c.handler();
  s.feed("abcdefghijk", h);  // over the limit: reported now, with its start
  s.feed("lmnop", h);        // still the same line: dropped
  s.feed("qr\nok\n", h);
  ASSERT_EQ(c.lines.size(), 2u);
  EXPECT_EQ(c.lines[0], "abcdefgh");
  EXPECT_TRUE(c.oversize[0]);
  EXPECT_EQ(c.lines[1], "ok");
  EXPECT_FALSE(c.oversize[1]);
  EXPECT_EQ(s.oversize_lines(), 1u);
  EXPECT_EQ(s.bytes_discarded(), 3u + 5u + 2u);
}

TEST(LineSplitter, TenMegabytesWithoutNewlineKeepMemoryBounded) {
  LineSplitter s(1024);
  Collected c;
  const auto h = c.handler();
  const std::string chunk(4096, 'x');
  std::size_t max_buffered = 0;
  for (int i = 0; i < 10 * 256; ++i) {  // 10 MiB
    s.feed(chunk, h);
    max_buffered = std::max(max_buffered, s.buffered());
  }
  EXPECT_LE(max_buffered, 1024u);
  EXPECT_EQ(s.oversize_lines(), 1u);
  EXPECT_EQ(c.lines.size(), 1u);
  s.feed("\n7\t1.00\n", h);  // the stream recovers at the next newline
  ASSERT_EQ(c.lines.size(), 2u);
  EXPECT_EQ(c.lines.back(), "7\t1.00");
}

TEST(LineSplitter, ResetDropsThePartialLine) {
  LineSplitter s(64);
  Collected c;
  s.feed("12\t0.", c.handler());
  EXPECT_EQ(s.reset(), 5u);
  s.feed("5\n", c.handler());
  ASSERT_EQ(c.lines.size(), 1u);
  EXPECT_EQ(c.lines[0], "5");
}
