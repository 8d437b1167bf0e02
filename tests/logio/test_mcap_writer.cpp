// McapWriter's file read back by hand (tests/support/mcap_records.hpp), against the spec:
// magic at both ends, Header first, Footer last, Data End closing the data section with the CRC
// of every byte before it, the summary grouped by opcode where the Footer and the Summary Offsets
// point, chunks with their CRC, Message Indexes and Chunk Indexes that lead to each message, and
// the Statistics. Both with chunks and without.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "mcap_records.hpp"
#include "spindown/crc32.hpp"
#include "spindown/mcap_writer.hpp"

namespace spindown {
namespace {

using testing::le;
using testing::mcap_records;
using testing::mcap_string;
using testing::McapRecord;

constexpr std::uint8_t op(McapOp o) { return static_cast<std::uint8_t>(o); }

struct Written {
  std::string bytes;
  McapStatistics stats;
};

// Two schemas, three channels, 40 messages with times out of order on purpose.
Written write_sample(std::size_t chunk_bytes) {
  std::ostringstream out(std::ios::binary);
  McapWriter w(out, {.profile = "", .library = "test", .chunk_bytes = chunk_bytes});
  const auto s1 = w.add_schema("a", "jsonschema", R"({"type":"object"})");
  const auto s2 = w.add_schema("b", "jsonschema", R"({"type":"object","title":"b"})");
  const auto c1 = w.add_channel(s1, "SPINDOWN.b1.SAMPLE", "json", {{"k", "v"}});
  const auto c2 = w.add_channel(s2, "SPINDOWN.b1.FIT", "json");
  const auto c3 = w.add_channel(s1, "SPINDOWN.b2.SAMPLE", "json");
  for (int i = 0; i < 40; ++i) {
    const std::uint16_t ch = i % 7 == 3 ? c2 : (i % 2 ? c3 : c1);
    const std::uint64_t t = 1'000'000'000ull + 1000ull * static_cast<std::uint64_t>(i ^ 5);
    w.write_message(ch, static_cast<std::uint32_t>(i), t, t + 1, "{\"i\":" + std::to_string(i) + "}");
  }
  w.close();
  EXPECT_EQ(w.bytes_written(), out.str().size());
  return {out.str(), w.statistics()};
}

// Where the Footer says the summary and its offsets are.
struct Layout {
  std::size_t footer_at = 0;
  std::uint64_t summary_start = 0, summary_offset_start = 0;
};

// What the messages showed, from the chunks or the data section.
struct Seen {
  std::map<std::uint16_t, std::uint64_t> counts;
  std::uint64_t messages = 0, first = ~0ull, last = 0;
  std::size_t chunks = 0;
};

// Magic at both ends, the Footer last (its offsets and the summary's CRC), the Header first, and
// Data End just before the summary with the CRC of every byte before it.
void check_frame(std::string_view b, Layout& l) {
  ASSERT_GT(b.size(), 16u + 29u);
  EXPECT_EQ(b.substr(0, 8), std::string_view(mcap_magic, 8));
  EXPECT_EQ(b.substr(b.size() - 8), std::string_view(mcap_magic, 8));
  EXPECT_EQ(static_cast<unsigned char>(b[0]), 0x89);

  // Footer: the last record, 20 bytes of content.
  l.footer_at = b.size() - 8 - 29;
  ASSERT_EQ(static_cast<std::uint8_t>(b[l.footer_at]), op(McapOp::footer));
  ASSERT_EQ(le(b, l.footer_at + 1, 8), 20u);
  l.summary_start = le(b, l.footer_at + 9, 8);
  l.summary_offset_start = le(b, l.footer_at + 17, 8);
  const std::uint32_t summary_crc = static_cast<std::uint32_t>(le(b, l.footer_at + 25, 4));
  ASSERT_GT(l.summary_start, 0u);
  ASSERT_GT(l.summary_offset_start, l.summary_start);
  ASSERT_LT(l.summary_offset_start, l.footer_at);
  EXPECT_EQ(summary_crc, crc32(b.substr(l.summary_start, l.footer_at + 25 - l.summary_start)))
      << "CRC of the summary through the footer's two offsets";

  // Everything between the magics is records: Header first, Footer last.
  const auto all = mcap_records(b, 8, b.size() - 8);
  ASSERT_GE(all.size(), 4u);
  EXPECT_EQ(all.front().op, op(McapOp::header));
  EXPECT_EQ(all.back().op, op(McapOp::footer));
  std::size_t at = 0;
  EXPECT_EQ(mcap_string(all.front().body, &at), "");
  EXPECT_EQ(mcap_string(all.front().body, &at), "test");

  const auto data = mcap_records(b, 8, l.summary_start);
  ASSERT_EQ(data.back().op, op(McapOp::data_end));
  EXPECT_EQ(data.back().offset + data.back().size(), l.summary_start);
  EXPECT_EQ(le(data.back().body, 0, 4), crc32(b.substr(0, data.back().offset)));
}

// One message as write_sample wrote it.
void check_message(const McapRecord& m, Seen& seen) {
  EXPECT_EQ(m.op, op(McapOp::message));
  const auto ch = static_cast<std::uint16_t>(le(m.body, 0, 2));
  const std::uint64_t t = le(m.body, 6, 8);
  EXPECT_EQ(le(m.body, 14, 8), t + 1) << "publish_time";
  const auto seq = le(m.body, 2, 4);
  EXPECT_EQ(m.body.substr(22), "{\"i\":" + std::to_string(seq) + "}");
  ++seen.counts[ch];
  ++seen.messages;
  seen.first = std::min(seen.first, t);
  seen.last = std::max(seen.last, t);
}

// A Chunk: its CRC, its messages and the time span it says they cover.
void check_chunk(const McapRecord& r, Seen& seen) {
  ++seen.chunks;
  const std::uint64_t size = le(r.body, 16, 8);
  const auto crc = static_cast<std::uint32_t>(le(r.body, 24, 4));
  std::size_t p = 28;
  EXPECT_EQ(mcap_string(r.body, &p), "") << "compression";
  ASSERT_EQ(le(r.body, p, 8), size);
  const std::string_view records = r.body.substr(p + 8, size);
  EXPECT_EQ(crc, crc32(records));
  std::uint64_t lo = ~0ull, hi = 0;
  for (const auto& m : mcap_records(records, 0, records.size())) {
    check_message(m, seen);
    lo = std::min(lo, le(m.body, 6, 8));
    hi = std::max(hi, le(m.body, 6, 8));
  }
  EXPECT_EQ(le(r.body, 0, 8), lo) << "message_start_time";
  EXPECT_EQ(le(r.body, 8, 8), hi) << "message_end_time";
}

// The data section's messages: in chunks when chunked, else loose; all 40, counted per channel as
// the writer's statistics say.
void check_data(std::string_view b, const Layout& l, const Written& w, bool chunked, Seen& seen) {
  for (const auto& r : mcap_records(b, 8, l.summary_start)) {
    if (r.op == op(McapOp::message)) {
      EXPECT_FALSE(chunked) << "a message outside the chunks";
      check_message(r, seen);
    }
    if (r.op != op(McapOp::chunk)) continue;
    EXPECT_TRUE(chunked);
    check_chunk(r, seen);
  }
  EXPECT_EQ(seen.messages, 40u);
  EXPECT_EQ(w.stats.message_count, 40u);
  EXPECT_EQ(seen.counts, (std::map<std::uint16_t, std::uint64_t>(w.stats.channel_message_counts.begin(),
                                                                 w.stats.channel_message_counts.end())));
}

// The summary: grouped by opcode, every group where its Summary Offset says.
void check_summary_groups(std::string_view b, const Layout& l, bool chunked) {
  std::vector<std::uint8_t> order;
  for (const auto& r : mcap_records(b, l.summary_start, l.summary_offset_start))
    if (order.empty() || order.back() != r.op) order.push_back(r.op);
  std::vector<std::uint8_t> want = {op(McapOp::schema), op(McapOp::channel), op(McapOp::statistics)};
  if (chunked) want.push_back(op(McapOp::chunk_index));
  EXPECT_EQ(order, want);
  const auto offsets = mcap_records(b, l.summary_offset_start, l.footer_at);
  ASSERT_EQ(offsets.size(), want.size());
  for (std::size_t i = 0; i < offsets.size(); ++i) {
    const auto& so = offsets[i];
    EXPECT_EQ(so.op, op(McapOp::summary_offset));
    const auto group = static_cast<std::uint8_t>(so.body[0]);
    EXPECT_EQ(group, want[i]);
    const std::uint64_t start = le(so.body, 1, 8), length = le(so.body, 9, 8);
    for (const auto& r : mcap_records(b, start, start + length)) EXPECT_EQ(r.op, group);
  }
}

void check_schema(const McapRecord& r, std::size_t number) {
  std::size_t p = 2;
  EXPECT_EQ(le(r.body, 0, 2), number);
  EXPECT_EQ(mcap_string(r.body, &p), number == 1 ? "a" : "b");
  EXPECT_EQ(mcap_string(r.body, &p), "jsonschema");
}

void check_channel(const McapRecord& r, std::size_t number) {
  std::size_t p = 4;
  EXPECT_EQ(le(r.body, 0, 2), number);
  const auto topic = mcap_string(r.body, &p);
  EXPECT_TRUE(topic.starts_with("SPINDOWN.")) << topic;
  EXPECT_EQ(mcap_string(r.body, &p), "json");
  if (number == 1) {
    ASSERT_EQ(le(r.body, p, 4), 10u) << "metadata map of one pair";
    p += 4;
    EXPECT_EQ(mcap_string(r.body, &p), "k");
    EXPECT_EQ(mcap_string(r.body, &p), "v");
  }
}

void check_statistics(const McapRecord& r, Seen& seen) {
  EXPECT_EQ(le(r.body, 0, 8), 40u);
  EXPECT_EQ(le(r.body, 8, 2), 2u);
  EXPECT_EQ(le(r.body, 10, 4), 3u);
  EXPECT_EQ(le(r.body, 22, 4), seen.chunks);
  EXPECT_EQ(le(r.body, 26, 8), seen.first);
  EXPECT_EQ(le(r.body, 34, 8), seen.last);
  EXPECT_EQ(le(r.body, 42, 4), 3u * 10u) << "three channels' message counts";
  for (std::size_t p = 46; p < r.body.size(); p += 10)
    EXPECT_EQ(le(r.body, p + 2, 8), seen.counts[static_cast<std::uint16_t>(le(r.body, p, 2))]);
}

// A Chunk Index: the chunk it points at, and each Message Index after it, which lead to every
// message.
void check_chunk_index(std::string_view b, const McapRecord& r, const Layout& l) {
  const std::uint64_t chunk_at = le(r.body, 16, 8), chunk_len = le(r.body, 24, 8);
  ASSERT_EQ(static_cast<std::uint8_t>(b[chunk_at]), op(McapOp::chunk));
  ASSERT_EQ(9 + le(b, chunk_at + 1, 8), chunk_len);
  EXPECT_EQ(le(r.body, 0, 8), le(b, chunk_at + 9, 8));
  const std::string_view records = b.substr(chunk_at + 9 + 40, le(b, chunk_at + 9 + 16, 8));
  const std::uint64_t map_len = le(r.body, 32, 4);
  std::uint64_t index_bytes = 0;
  for (std::size_t p = 36; p < 36 + map_len; p += 10) {
    const auto ch = le(r.body, p, 2);
    const std::uint64_t mi = le(r.body, p + 2, 8);
    ASSERT_EQ(static_cast<std::uint8_t>(b[mi]), op(McapOp::message_index));
    const auto body = mcap_records(b, mi, mi + 9 + le(b, mi + 1, 8)).at(0).body;
    index_bytes += 9 + body.size();
    EXPECT_EQ(le(body, 0, 2), ch);
    const std::uint64_t n = le(body, 2, 4);
    for (std::size_t e = 6; e < 6 + n; e += 16) {
      const std::uint64_t t = le(body, e, 8), off = le(body, e + 8, 8);
      const auto m = mcap_records(records, off, off + 9 + le(records, off + 1, 8)).at(0);
      EXPECT_EQ(m.op, op(McapOp::message));
      EXPECT_EQ(le(m.body, 0, 2), ch);
      EXPECT_EQ(le(m.body, 6, 8), t);
    }
  }
  EXPECT_EQ(le(r.body, 36 + map_len, 8), index_bytes) << "message_index_length";
  EXPECT_EQ(chunk_at + chunk_len + index_bytes <= l.summary_start, true);
}

// The summary's records: 2 schemas, 3 channels, the statistics of what the data held, an index for
// every chunk.
void check_summary_records(std::string_view b, const Layout& l, const Written& w, Seen& seen) {
  std::size_t schemas = 0, channels = 0, chunk_indexes = 0;
  for (const auto& r : mcap_records(b, l.summary_start, l.summary_offset_start)) {
    if (r.op == op(McapOp::schema)) {
      check_schema(r, ++schemas);
    } else if (r.op == op(McapOp::channel)) {
      check_channel(r, ++channels);
    } else if (r.op == op(McapOp::statistics)) {
      check_statistics(r, seen);
    } else if (r.op == op(McapOp::chunk_index)) {
      ++chunk_indexes;
      check_chunk_index(b, r, l);
    }
  }
  EXPECT_EQ(schemas, 2u);
  EXPECT_EQ(channels, 3u);
  EXPECT_EQ(chunk_indexes, seen.chunks);
  EXPECT_EQ(w.stats.chunk_count, seen.chunks);
}

void check_file(const Written& w, bool chunked) {
  const std::string_view b = w.bytes;
  Layout l;
  ASSERT_NO_FATAL_FAILURE(check_frame(b, l));
  Seen seen;
  ASSERT_NO_FATAL_FAILURE(check_data(b, l, w, chunked, seen));
  ASSERT_NO_FATAL_FAILURE(check_summary_groups(b, l, chunked));
  check_summary_records(b, l, w, seen);
}

TEST(McapWriter, ChunkedFileMatchesTheSpec) {
  const Written w = write_sample(200);  // several chunks of a few messages
  check_file(w, true);
  EXPECT_GE(w.stats.chunk_count, 3u);
}

TEST(McapWriter, UnchunkedFileMatchesTheSpec) {
  const Written w = write_sample(0);
  check_file(w, false);
  EXPECT_EQ(w.stats.chunk_count, 0u);
}

TEST(McapWriter, EmptyFileIsHeaderDataEndSummaryAndFooter) {
  std::ostringstream out(std::ios::binary);
  McapWriter w(out);
  w.close();
  const auto all = mcap_records(out.str(), 8, out.str().size() - 8);
  std::vector<std::uint8_t> ops;
  for (const auto& r : all) ops.push_back(r.op);
  EXPECT_EQ(ops, (std::vector<std::uint8_t>{op(McapOp::header), op(McapOp::data_end), op(McapOp::statistics),
                                            op(McapOp::summary_offset), op(McapOp::footer)}));
}

TEST(McapWriter, UnknownChannelOrSchemaIsRefused) {
  std::ostringstream out(std::ios::binary);
  McapWriter w(out);
  EXPECT_THROW(w.write_message(1, 0, 1, 1, "{}"), std::invalid_argument);
  EXPECT_THROW(w.add_channel(3, "t", "json"), std::invalid_argument);
  const auto c = w.add_channel(0, "t", "json");
  EXPECT_NO_THROW(w.write_message(c, 0, 1, 1, "{}"));
}

}  // namespace
}  // namespace spindown
