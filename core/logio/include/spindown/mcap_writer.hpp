#pragma once
// A writer of MCAP files (https://mcap.dev/spec, major version 0), the container Foxglove and
// PlotJuggler open: schemas, channels and timestamped messages, nothing else (no attachments,
// no metadata, no compression). Debian has no libmcap, and this much of the format is small.
//
// File layout, as the spec's "Multiple Messages with Chunk Indices" diagram:
//   <Magic><Header>
//   data section: Schema and Channel records as they are added (outside chunks), Chunk records
//     of messages (uncompressed, CRC of their records), each followed by one Message Index per
//     channel in it; then Data End (CRC of every byte before it, magic included)
//   summary section, grouped by opcode: every Schema, every Channel, one Statistics, one Chunk
//     Index per chunk
//   summary offset section: one Summary Offset per group
//   <Footer: summary_start, summary_offset_start, CRC of the summary through these two><Magic>
// With chunk_bytes 0 messages go straight into the data section (no chunks, no indexes).
// Integers are little-endian; times are nanoseconds since the Unix epoch.
#include <cstdint>
#include <map>
#include <ostream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace spindown {

inline constexpr char mcap_magic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Record opcodes (spec "Records").
enum class McapOp : std::uint8_t {
  header = 0x01,
  footer = 0x02,
  schema = 0x03,
  channel = 0x04,
  message = 0x05,
  chunk = 0x06,
  message_index = 0x07,
  chunk_index = 0x08,
  statistics = 0x0B,
  summary_offset = 0x0E,
  data_end = 0x0F,
};

struct McapWriterOptions {
  std::string profile;                  // Header.profile ("" = none)
  std::string library = "spindown";     // Header.library
  std::size_t chunk_bytes = 1u << 20;   // a chunk is closed past this many bytes of records; 0 = no chunks
};

struct McapStatistics {
  std::uint64_t message_count = 0;
  std::uint16_t schema_count = 0;
  std::uint32_t channel_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time = 0, message_end_time = 0;  // 0 without messages
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;
};

class McapWriter {
 public:
  // Writes the magic and the Header at once. out must be binary and outlive the writer.
  explicit McapWriter(std::ostream& out, McapWriterOptions options = {});
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // New ids from 1. data must follow encoding ("jsonschema": a JSON Schema document).
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  // schema_id 0: no schema. message_encoding e.g. "json".
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                            const std::vector<std::pair<std::string, std::string>>& metadata = {});
  // channel_id must come from add_channel (std::invalid_argument otherwise).
  void write_message(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns,
                     std::uint64_t publish_time_ns, std::string_view data);
  // The last chunk, Data End, summary, summary offsets, Footer and the closing magic. Nothing
  // may be written afterwards; a writer never closed leaves a file without its footer.
  void close();

  bool good() const { return out_.good(); }
  std::uint64_t bytes_written() const { return offset_; }
  const McapStatistics& statistics() const { return stats_; }

 private:
  struct ChunkIndex {
    std::uint64_t start_time, end_time, offset, length, message_index_length, records_size;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets;
  };
  void emit(std::string_view bytes);  // to out_, counted, into the data section's CRC while open
  void flush_chunk();

  std::ostream& out_;
  McapWriterOptions o_;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  bool in_data_section_ = true, closed_ = false;
  std::vector<std::string> schema_records_, channel_records_;
  McapStatistics stats_;
  // The open chunk: its records, its time span, and per channel (log_time, offset in records).
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_has_messages_ = false;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  std::vector<ChunkIndex> chunk_indexes_;
};

}  // namespace spindown
