#include "spindown/mcap_writer.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "spindown/crc32.hpp"

namespace spindown {

namespace {

// Little-endian fields (spec "Serialization").
void put_u8(std::string& s, std::uint8_t v) { s.push_back(static_cast<char>(v)); }
void put_u16(std::string& s, std::uint16_t v) {
  for (int i = 0; i < 2; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_u32(std::string& s, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_u64(std::string& s, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) s.push_back(static_cast<char>((v >> (8 * i)) & 0xFF));
}
void put_string(std::string& s, std::string_view v) {
  put_u32(s, static_cast<std::uint32_t>(v.size()));
  s.append(v);
}
// <opcode><uint64 content length><content>
std::string record(McapOp op, std::string_view content) {
  std::string r;
  r.reserve(9 + content.size());
  put_u8(r, static_cast<std::uint8_t>(op));
  put_u64(r, content.size());
  r.append(content);
  return r;
}
void append_record(std::string& out, McapOp op, std::string_view content) {
  put_u8(out, static_cast<std::uint8_t>(op));
  put_u64(out, content.size());
  out.append(content);
}

}  // namespace

McapWriter::McapWriter(std::ostream& out, McapWriterOptions options) : out_(out), o_(std::move(options)) {
  emit(std::string_view(mcap_magic, sizeof mcap_magic));
  std::string h;
  put_string(h, o_.profile);
  put_string(h, o_.library);
  emit(record(McapOp::header, h));
}

void McapWriter::emit(std::string_view bytes) {
  out_.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  offset_ += bytes.size();
  if (in_data_section_) data_crc_ = crc32_update(data_crc_, bytes.data(), bytes.size());
}

std::uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding, std::string_view data) {
  if (closed_) throw std::logic_error("McapWriter: add_schema after close");
  if (schema_records_.size() >= 0xFFFE) throw std::length_error("McapWriter: more than 65534 schemas");
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);
  std::string c;
  put_u16(c, id);
  put_string(c, name);
  put_string(c, encoding);
  put_string(c, data);  // uint32 length-prefixed bytes
  schema_records_.push_back(record(McapOp::schema, c));
  emit(schema_records_.back());
  stats_.schema_count = id;
  return id;
}

std::uint16_t McapWriter::add_channel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                      const std::vector<std::pair<std::string, std::string>>& metadata) {
  if (closed_) throw std::logic_error("McapWriter: add_channel after close");
  if (schema_id > schema_records_.size())
    throw std::invalid_argument(fmt::format("McapWriter: channel '{}' names schema {}, which was not added", topic, schema_id));
  if (channel_records_.size() >= 0xFFFF) throw std::length_error("McapWriter: more than 65535 channels");
  const auto id = static_cast<std::uint16_t>(channel_records_.size() + 1);
  std::string c;
  put_u16(c, id);
  put_u16(c, schema_id);
  put_string(c, topic);
  put_string(c, message_encoding);
  std::string map;
  for (const auto& [k, v] : metadata) {
    put_string(map, k);
    put_string(map, v);
  }
  put_u32(c, static_cast<std::uint32_t>(map.size()));
  c += map;
  channel_records_.push_back(record(McapOp::channel, c));
  emit(channel_records_.back());
  stats_.channel_count = id;
  return id;
}

void McapWriter::write_message(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns,
                               std::uint64_t publish_time_ns, std::string_view data) {
  if (closed_) throw std::logic_error("McapWriter: write_message after close");
  if (channel_id == 0 || channel_id > channel_records_.size())
    throw std::invalid_argument(fmt::format("McapWriter: message on channel {}, which was not added", channel_id));
  std::string c;
  c.reserve(22 + data.size());
  put_u16(c, channel_id);
  put_u32(c, sequence);
  put_u64(c, log_time_ns);
  put_u64(c, publish_time_ns);
  c.append(data);

  if (stats_.message_count == 0) {
    stats_.message_start_time = stats_.message_end_time = log_time_ns;
  } else {
    stats_.message_start_time = std::min(stats_.message_start_time, log_time_ns);
    stats_.message_end_time = std::max(stats_.message_end_time, log_time_ns);
  }
  ++stats_.message_count;
  ++stats_.channel_message_counts[channel_id];

  if (o_.chunk_bytes == 0) {
    emit(record(McapOp::message, c));
    return;
  }
  if (!chunk_has_messages_) {
    chunk_start_ = chunk_end_ = log_time_ns;
    chunk_has_messages_ = true;
  } else {
    chunk_start_ = std::min(chunk_start_, log_time_ns);
    chunk_end_ = std::max(chunk_end_, log_time_ns);
  }
  chunk_index_[channel_id].emplace_back(log_time_ns, chunk_.size());
  append_record(chunk_, McapOp::message, c);
  if (chunk_.size() >= o_.chunk_bytes) flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  ChunkIndex ix{};
  ix.start_time = chunk_start_;
  ix.end_time = chunk_end_;
  ix.offset = offset_;
  ix.records_size = chunk_.size();
  std::string c;
  c.reserve(40 + chunk_.size());
  put_u64(c, chunk_start_);
  put_u64(c, chunk_end_);
  put_u64(c, chunk_.size());             // uncompressed_size
  put_u32(c, crc32(chunk_));             // uncompressed_crc
  put_string(c, "");                     // compression: none
  put_u64(c, chunk_.size());             // records, uint64 length-prefixed
  c += chunk_;
  const std::string r = record(McapOp::chunk, c);
  ix.length = r.size();
  emit(r);

  const std::uint64_t index_start = offset_;
  for (const auto& [channel, entries] : chunk_index_) {  // std::map: in channel order
    std::string m;
    put_u16(m, channel);
    put_u32(m, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [t, off] : entries) {
      put_u64(m, t);
      put_u64(m, off);
    }
    ix.message_index_offsets.emplace_back(channel, offset_);
    emit(record(McapOp::message_index, m));
  }
  ix.message_index_length = offset_ - index_start;
  chunk_indexes_.push_back(std::move(ix));
  ++stats_.chunk_count;

  chunk_.clear();
  chunk_index_.clear();
  chunk_has_messages_ = false;
  chunk_start_ = chunk_end_ = 0;
}

void McapWriter::close() {
  if (closed_) return;
  flush_chunk();
  std::string de;
  put_u32(de, data_crc_);  // every byte from the leading magic up to this record
  in_data_section_ = false;
  emit(record(McapOp::data_end, de));
  closed_ = true;

  // The summary section, grouped by opcode; its CRC runs on through the footer's offsets.
  const std::uint64_t summary_start = offset_;
  std::uint32_t summary_crc = 0;
  struct Group {
    McapOp op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](McapOp op, const std::vector<std::string>& records) {
    if (records.empty()) return;
    const std::uint64_t start = offset_;
    for (const auto& r : records) {
      emit(r);
      summary_crc = crc32_update(summary_crc, r.data(), r.size());
    }
    groups.push_back({op, start, offset_ - start});
  };
  group(McapOp::schema, schema_records_);
  group(McapOp::channel, channel_records_);

  std::string st;
  put_u64(st, stats_.message_count);
  put_u16(st, stats_.schema_count);
  put_u32(st, stats_.channel_count);
  put_u32(st, 0);  // attachments
  put_u32(st, 0);  // metadata
  put_u32(st, stats_.chunk_count);
  put_u64(st, stats_.message_start_time);
  put_u64(st, stats_.message_end_time);
  std::string counts;
  for (const auto& [channel, n] : stats_.channel_message_counts) {
    put_u16(counts, channel);
    put_u64(counts, n);
  }
  put_u32(st, static_cast<std::uint32_t>(counts.size()));
  st += counts;
  group(McapOp::statistics, {record(McapOp::statistics, st)});

  std::vector<std::string> indexes;
  for (const ChunkIndex& ix : chunk_indexes_) {
    std::string c;
    put_u64(c, ix.start_time);
    put_u64(c, ix.end_time);
    put_u64(c, ix.offset);
    put_u64(c, ix.length);
    put_u32(c, static_cast<std::uint32_t>(ix.message_index_offsets.size() * 10));
    for (const auto& [channel, off] : ix.message_index_offsets) {
      put_u16(c, channel);
      put_u64(c, off);
    }
    put_u64(c, ix.message_index_length);
    put_string(c, "");
    put_u64(c, ix.records_size);  // compressed_size
    put_u64(c, ix.records_size);  // uncompressed_size
    indexes.push_back(record(McapOp::chunk_index, c));
  }
  group(McapOp::chunk_index, indexes);

  const std::uint64_t summary_offset_start = offset_;
  for (const Group& g : groups) {
    std::string so;
    put_u8(so, static_cast<std::uint8_t>(g.op));
    put_u64(so, g.start);
    put_u64(so, g.length);
    const std::string r = record(McapOp::summary_offset, so);
    emit(r);
    summary_crc = crc32_update(summary_crc, r.data(), r.size());
  }

  // Footer: the CRC covers the summary, the summary offsets and the footer up to the CRC itself.
  std::string f;
  put_u8(f, static_cast<std::uint8_t>(McapOp::footer));
  put_u64(f, 20);
  put_u64(f, summary_start);
  put_u64(f, summary_offset_start);
  summary_crc = crc32_update(summary_crc, f.data(), f.size());
  put_u32(f, summary_crc);
  emit(f);
  emit(std::string_view(mcap_magic, sizeof mcap_magic));
  out_.flush();
}

}  // namespace spindown
