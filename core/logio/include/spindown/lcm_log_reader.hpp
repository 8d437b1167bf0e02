#pragma once
// LCM event logs (what lcm-logger and spindown-logger write), read with the log's own
// timestamps — never by file:// replay, which hands out wall-clock times (design §7).
// LcmLogReader streams events one at a time from one reusable block buffer (the file is read
// forward in 1 MiB blocks, events parsed in place; no seeks), so a refit never holds a whole log
// in memory; read_lcm_log() gathers one Recording per bench from SPINDOWN.<bench>.SAMPLE and
// the latest SPINDOWN.<bench>.CONFIG.
//
// Event layout (lcm_eventlog): uint32 0xEDA1DA01, int64 event number, int64 timestamp (µs),
// int32 channel length, int32 data length (all big-endian), channel bytes, data bytes.
//
// A damaged log is read as far as it can be: garbage between events is skipped to the next
// event marker, a truncated last event or an undecodable message is reported (with its event
// number, channel and byte offset) and reading goes on.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/samples_t.hpp>

#include "spindown/bench.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/recording.hpp"
#include "spindown/sample_stream.hpp"
#include "spindown/short_name_cache.hpp"

namespace spindown {

// Every LCM log event starts with this big-endian word (and so does the file).
inline constexpr std::uint32_t lcm_log_magic = 0xEDA1DA01u;

// "SPINDOWN.<bench>.<KIND>" with a valid bench id ([A-Za-z0-9_-]{1,32}); nullopt otherwise.
struct SpindownChannelName {
  std::string_view bench;
  std::string_view kind;  // "SAMPLE", "CONFIG", …
};
std::optional<SpindownChannelName> split_spindown_channel(std::string_view channel);

struct LcmLogEvent {
  enum class Kind {
    samples,  // a decoded samples_t from SPINDOWN.<bench>.SAMPLE
    config,   // a decoded config_t from SPINDOWN.<bench>.CONFIG
    other,    // any other channel: raw payload only
    problem,  // an event that could not be used, or damage in the file itself
  };
  Kind kind = Kind::other;
  std::int64_t number = 0;       // 1-based position of the event in the file (0: file damage)
  std::int64_t log_utime = 0;    // receive time the logger wrote (µs since the Unix epoch)
  std::int64_t file_offset = 0;  // byte offset of the event (or of the damage)
  // Views into the reader (no copy per event), valid until the next next(): the channel name as
  // the event has it (empty for damage in the file) and, for SPINDOWN.<bench>.* channels, the
  // bench id (else empty). The bench views the reader's channel table, not the file buffer; it
  // happens to outlive next() for channels within max_channel_ids, but callers copy it anyway.
  std::string_view channel;
  // The channel name's index in this reader, the same for every event on it (a consumer's
  // per-channel cache needs no string compare); -1 past LcmLogReader::max_channel_ids distinct names.
  std::int32_t channel_id = -1;
  std::string_view bench;
  SamplesView samples_view;      // Kind::samples: the message in place, valid until the next next()
  samples_t samples{};             // Kind::samples, unless the reader was made with LcmSamples::view_only
  config_t config{};               // Kind::config
  const void* data = nullptr;    // Kind::other: the payload, valid until the next next()
  std::int32_t data_size = 0;
  std::string problem;           // Kind::problem: what was wrong and what was done
};

// What a SAMPLE event carries. A consumer that reads the view only (refit) spares building a
// samples_t per message, which dominates a one-sample message.
enum class LcmSamples { view_and_message, view_only };

class LcmLogReader {
 public:
  explicit LcmLogReader(const std::string& path, LcmSamples samples = LcmSamples::view_and_message);
  ~LcmLogReader();
  LcmLogReader(const LcmLogReader&) = delete;
  LcmLogReader& operator=(const LcmLogReader&) = delete;

  // False when the file could not be opened; open_error() says why (with errno text).
  bool good() const { return fd_ >= 0; }
  const std::string& open_error() const { return open_error_; }
  const std::string& path() const { return path_; }

  // The next event (or problem); false at the end of the log. event is reused between calls
  // (its vectors keep their capacity); event.data points into the reader's buffer.
  bool next(LcmLogEvent& event);

  std::int64_t events_read() const { return events_; }
  std::int64_t file_size() const { return size_; }

  // Distinct channel names remembered (with their id); more are parsed per event.
  static constexpr std::size_t max_channel_ids = 256;

 private:
  // What a channel name means, worked out once per distinct name (a log has a handful).
  struct ChannelInfo {
    std::string channel;
    std::string bench;      // empty: not SPINDOWN.<bench>.<KIND>
    int kind = 0;           // 0 other, 1 SAMPLE, 2 CONFIG
    std::int32_t id = -1;
  };
  inline const ChannelInfo& channel_info(std::string_view channel);
  const ChannelInfo& find_channel(std::string_view channel);  // channel_info() past the cache
  bool next_checked(LcmLogEvent& event);  // next() for all but a whole, sound, buffered event
  inline void accept(LcmLogEvent& event, const unsigned char* p, std::int32_t channel_len, std::int32_t data_len);
  // Makes n bytes from pos_ available in the buffer (fewer only at the end of the file or on a
  // read error); returns how many are and points *p at the first.
  std::int64_t fill(std::int64_t n, const unsigned char** p) {
    if (pos_ >= buffer_offset_ && buffer_offset_ + buffered_ - pos_ >= n) {  // nearly always
      *p = buffer_.get() + (pos_ - buffer_offset_);
      return n;
    }
    return refill(n, p);
  }
  std::int64_t refill(std::int64_t n, const unsigned char** p);  // fill() when a read is needed
  // Offset of the first event marker at or after from, or -1 when none follows.
  std::int64_t find_marker(std::int64_t from);
  bool find_event_start(LcmLogEvent& event);
  inline void decode(LcmLogEvent& event, const ChannelInfo& info, const void* data, std::int32_t size);
  void recheck_samples(LcmLogEvent& event, const void* data, std::int32_t size);  // decode()'s rare path

  std::string path_;
  LcmSamples samples_;
  std::string open_error_;
  int fd_ = -1;
  std::int64_t size_ = 0;
  std::int64_t events_ = 0;
  bool done_ = false;
  // File bytes [buffer_offset_, buffer_offset_ + buffered_) in buffer_capacity_ bytes, never
  // zero-filled (read(2) writes them before they are parsed).
  std::unique_ptr<unsigned char[]> buffer_;
  std::int64_t buffer_capacity_ = 0;
  std::int64_t buffer_offset_ = 0;
  std::int64_t buffered_ = 0;
  std::int64_t pos_ = 0;               // file offset of the next byte to parse
  std::string read_error_;             // a failed read(2), reported once as a problem
  std::deque<ChannelInfo> channels_;   // a deque: entries stay put as it grows
  ChannelInfo uncached_;               // the name being read when channels_ is full
  ShortNameCache<const ChannelInfo> channel_cache_;  // entries of channels_ only
};

struct LcmLogOptions {
  std::size_t max_event_reports = 20;  // problems per bench listed one by one before a count
  // Whose SAMPLE and CONFIG are read: the lab (default: every lab) and with a key only signed ones
  // (message_gate.hpp); the others are named and skipped.
  MessageGateOptions gate = MessageGateOptions::every_lab();
  SampleStreamOptions stream;          // the samples' sources and far jumps (sample_stream.hpp)
  bool is_valid(std::string* why) const;
};

struct BenchLog {
  std::string bench;
  Recording recording;               // source "FILE SPINDOWN.<bench>.SAMPLE"; line = event number
  std::optional<config_t> config;    // the latest SPINDOWN.<bench>.CONFIG
  std::int64_t sample_messages = 0;
  std::int64_t config_messages = 0;
  std::int64_t samples_lost = 0;     // from gaps in samples_t.seq
  std::int64_t refused_messages = 0; // SAMPLE and CONFIG the gate refused (another lab, unsigned, …)
  std::int64_t new_sources = 0;      // other sources that took over the stream (restarted bridges)
};

struct LcmLogContents {
  std::string path;
  std::vector<BenchLog> benches;                      // in order of first appearance
  std::vector<Diagnostic> diagnostics;                // about the file as a whole
  std::map<std::string, std::int64_t> other_channels; // events not read as samples or config
  std::int64_t events = 0;
  bool has_errors() const;
};

LcmLogContents read_lcm_log(const std::string& path, const LcmLogOptions& options = {});

// J and K_b from a config message when they are usable; otherwise nullopt and *why.
std::optional<BenchParams> bench_params_from_config(const config_t& config, std::string* why = nullptr);

}  // namespace spindown
