#include "spindown/lcm_log_reader.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <limits>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "spindown/short_string_equal.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/text_support.hpp"

namespace spindown {

namespace {

constexpr std::int64_t event_header_bytes = 28;  // magic, event number, timestamp, 2 lengths
constexpr std::int32_t max_channel_bytes = 1000; // lcm_eventlog's own limit

// One load and a byte swap each (the byte-by-byte form was not always turned into one).
std::uint32_t be32(const unsigned char* p) { return static_cast<std::uint32_t>(SamplesView::load_be32(p)); }
std::uint64_t be64(const unsigned char* p) { return SamplesView::load_be64(p); }

bool is_bench_char(char c) {
  return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
}

std::string printable(std::string_view s) { return text::quote_line(s); }

}  // namespace

std::optional<SpindownChannelName> split_spindown_channel(std::string_view channel) {
  constexpr std::string_view prefix = "SPINDOWN.";
  if (!channel.starts_with(prefix)) return std::nullopt;
  const std::string_view rest = channel.substr(prefix.size());
  const std::size_t dot = rest.find('.');
  if (dot == std::string_view::npos || dot == 0 || dot > 32) return std::nullopt;
  const std::string_view bench = rest.substr(0, dot), kind = rest.substr(dot + 1);
  if (kind.empty() || !std::all_of(bench.begin(), bench.end(), is_bench_char)) return std::nullopt;
  return SpindownChannelName{bench, kind};
}

std::optional<BenchParams> bench_params_from_config(const config_t& config, std::string* why) {
  BenchParams p;
  p.inertia_kg_m2 = config.inertia_kg_m2;
  p.kb_v_s_per_rad = config.kb_v_s_per_rad;
  p.inertia_source = config.inertia_source.empty() ? "config" : config.inertia_source;
  p.kb_source = config.kb_source.empty() ? "config" : config.kb_source;
  // A CONFIG's own uncertainties; a nonsense one (NaN, negative, ≥ 100 %) is not used.
  const auto rel = [](double x) { return std::isfinite(x) && x >= 0 && x < 1 ? x : 0.0; };
  p.inertia_rel_error = rel(config.inertia_rel_error);
  p.kb_rel_error = rel(config.kb_rel_error);
  std::string bad;
  if (!p.is_valid(&bad)) {
    if (why) *why = fmt::format("config of bench '{}': {}", text::escape_invalid_utf8(config.bench), bad);
    return std::nullopt;
  }
  return p;
}

// ---------------------------------------------------------------------------------------------
// LcmLogReader

namespace {
constexpr std::int64_t block_bytes = 1 << 20;  // one pread(2) per MiB, forward only
}

LcmLogReader::LcmLogReader(const std::string& path, LcmSamples samples) : path_(path), samples_(samples) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    open_error_ = fmt::format("cannot open {}: {}", path, std::strerror(errno));
    return;
  }
  if (S_ISDIR(st.st_mode)) {
    open_error_ = fmt::format("cannot read {}: it is a directory", path);
    return;
  }
  // open() would wait forever on a FIFO without a writer, and a device never ends.
  if (!S_ISREG(st.st_mode)) {
    open_error_ = fmt::format("cannot read {} as an LCM log: not a regular file (a pipe, FIFO or device)", path);
    return;
  }
  size_ = static_cast<std::int64_t>(st.st_size);
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd_ < 0) {
    open_error_ = fmt::format("cannot open {}: {}", path, std::strerror(errno));
    return;
  }
  ::posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

LcmLogReader::~LcmLogReader() {
  if (fd_ >= 0) ::close(fd_);
}

std::int64_t LcmLogReader::refill(std::int64_t n, const unsigned char** p) {
  const std::int64_t wanted = std::min(n, size_ - pos_);
  if (buffer_offset_ + buffered_ - pos_ < wanted && read_error_.empty()) {
    // Keep the unparsed tail, then read whole blocks behind it up to the size seen at open.
    const std::int64_t keep = std::max<std::int64_t>(buffer_offset_ + buffered_ - pos_, 0);
    const std::int64_t need = std::max(wanted, std::min(block_bytes, size_ - pos_));
    if (buffer_capacity_ < need) {
      const std::int64_t capacity = std::max(need, block_bytes);
      auto bigger = std::make_unique_for_overwrite<unsigned char[]>(static_cast<std::size_t>(capacity));
      if (keep > 0) std::memcpy(bigger.get(), buffer_.get() + (pos_ - buffer_offset_), static_cast<std::size_t>(keep));
      buffer_ = std::move(bigger);
      buffer_capacity_ = capacity;
    } else if (keep > 0 && pos_ != buffer_offset_) {
      std::memmove(buffer_.get(), buffer_.get() + (pos_ - buffer_offset_), static_cast<std::size_t>(keep));
    }
    buffer_offset_ = pos_;
    buffered_ = keep;
    const std::int64_t room = std::min<std::int64_t>(buffer_capacity_, size_ - pos_);
    while (buffered_ < room) {
      const ssize_t got = ::pread(fd_, buffer_.get() + buffered_, static_cast<std::size_t>(room - buffered_),
                                  static_cast<off_t>(buffer_offset_ + buffered_));
      if (got > 0) {
        buffered_ += got;
      } else if (got < 0 && errno == EINTR) {
        continue;
      } else {
        if (got < 0)
          read_error_ = fmt::format("read error at offset {}: {}", buffer_offset_ + buffered_, std::strerror(errno));
        else  // the file shrank since it was opened: what is there is all there is
          size_ = buffer_offset_ + buffered_;
        break;
      }
    }
  }
  *p = buffer_.get() + (pos_ - buffer_offset_);
  return std::clamp<std::int64_t>(buffer_offset_ + buffered_ - pos_, 0, std::max<std::int64_t>(wanted, 0));
}

std::int64_t LcmLogReader::find_marker(std::int64_t from) {
  pos_ = from;
  const unsigned char* p = nullptr;
  for (;;) {
    const std::int64_t have = fill(block_bytes, &p);
    if (have < 4) return -1;
    const unsigned char first = lcm_log_magic >> 24;
    for (const unsigned char* q = p; (q = static_cast<const unsigned char*>(std::memchr(q, first, static_cast<std::size_t>(p + have - 3 - q))));
         ++q) {
      if (be32(q) == lcm_log_magic) return pos_ + (q - p);
      if (q + 1 >= p + have - 3) break;
    }
    pos_ += have - 3;  // the last 3 bytes may start a marker that the next block completes
  }
}

[[gnu::always_inline]] inline const LcmLogReader::ChannelInfo& LcmLogReader::channel_info(std::string_view channel) {
  const ChannelInfo* cached = channel_cache_.slot(channel);
  if (cached && short_string_equal(cached->channel, channel)) return *cached;  // nearly always
  return find_channel(channel);
}

const LcmLogReader::ChannelInfo& LcmLogReader::find_channel(std::string_view channel) {
  const ChannelInfo* found = nullptr;
  for (const ChannelInfo& c : channels_)
    if (short_string_equal(c.channel, channel)) {
      found = &c;
      break;
    }
  if (!found) {
    ChannelInfo& info = channels_.size() < max_channel_ids ? channels_.emplace_back() : uncached_;
    info.channel.assign(channel);
    info.bench.clear();
    info.kind = 0;
    info.id = &info == &uncached_ ? -1 : static_cast<std::int32_t>(channels_.size() - 1);
    if (const auto name = split_spindown_channel(channel)) {
      info.bench.assign(name->bench);
      info.kind = name->kind == "SAMPLE" ? 1 : name->kind == "CONFIG" ? 2 : 0;
    }
    found = &info;
  }
  if (found->id >= 0) channel_cache_.slot(channel) = found;
  return *found;
}

// Positioned where no event starts: finds the next event marker and reports the skipped
// bytes. Always moves forward or ends the log.
bool LcmLogReader::find_event_start(LcmLogEvent& event) {
  const std::int64_t from = pos_;
  const std::int64_t at = find_marker(from);
  event.kind = LcmLogEvent::Kind::problem;
  event.number = 0;
  event.log_utime = 0;
  event.file_offset = from;
  event.channel_id = -1;
  event.channel = {};
  event.bench = {};
  event.data = nullptr;
  event.data_size = 0;
  if (at < 0) {
    done_ = true;
    pos_ = size_;
    event.problem = fmt::format("{} bytes at offset {} (after event {}) are not an LCM event and no event follows; "
                                "ignored",
                                size_ - from, from, events_);
    return true;
  }
  pos_ = at;
  event.problem = fmt::format("{} bytes at offset {} (after event {}) are not an LCM event; skipped to the next "
                              "event at offset {}",
                              at - from, from, events_, at);
  return true;
}

bool LcmLogReader::next(LcmLogEvent& event) {
  // Nearly every event: whole in the buffer with a sound header. The rest (the end, a refill,
  // damage) takes next_checked(), which reads this same event the same way when it is sound.
  const std::int64_t in_buffer = buffer_offset_ + buffered_ - pos_;
  if (fd_ >= 0 && !done_ && pos_ >= buffer_offset_ && in_buffer >= event_header_bytes) {
    const unsigned char* p = buffer_.get() + (pos_ - buffer_offset_);
    const std::int32_t channel_len = static_cast<std::int32_t>(be32(p + 20));
    const std::int32_t data_len = static_cast<std::int32_t>(be32(p + 24));
    if (be32(p) == lcm_log_magic && channel_len > 0 && channel_len < max_channel_bytes && data_len >= 0 &&
        event_header_bytes + channel_len + data_len <= in_buffer) {
      accept(event, p, channel_len, data_len);
      return true;
    }
  }
  return next_checked(event);
}

// A sound event whose bytes (header at p) are all in the buffer: kept, whatever follows it
// (another event, the end, or garbage that the next call skips and reports). Inlined into next()
// with the channel lookup and the decode: one flat function per event.
[[gnu::always_inline]] inline void LcmLogReader::accept(LcmLogEvent& event, const unsigned char* p,
                                                      std::int32_t channel_len, std::int32_t data_len) {
  event.file_offset = pos_;
  pos_ += event_header_bytes + channel_len + data_len;
  ++events_;
  event.number = events_;
  event.log_utime = static_cast<std::int64_t>(be64(p + 12));
  event.channel = std::string_view(reinterpret_cast<const char*>(p + event_header_bytes),
                                   static_cast<std::size_t>(channel_len));
  event.problem.clear();
  decode(event, channel_info(event.channel), p + event_header_bytes + channel_len, data_len);
}

bool LcmLogReader::next_checked(LcmLogEvent& event) {
  if (fd_ < 0 || done_) return false;
  const std::int64_t at = pos_;
  auto problem = [&](std::string text) {
    event.kind = LcmLogEvent::Kind::problem;
    event.number = 0;
    event.channel_id = -1;
    event.file_offset = at;
    event.data = nullptr;
    event.data_size = 0;
    event.problem = std::move(text);
    return true;
  };
  if (at >= size_) {
    done_ = true;
    return false;
  }
  const unsigned char* h = nullptr;
  const std::int64_t got = fill(event_header_bytes, &h);
  if (!read_error_.empty() && got < std::min(event_header_bytes, size_ - at)) {
    done_ = true;
    event.channel = {};
    event.bench = {};
    return problem(fmt::format("{} (after event {}); the rest of the log is not read", read_error_, events_));
  }
  if (got < 4 || be32(h) != lcm_log_magic) return find_event_start(event);

  event.channel = {};
  event.bench = {};
  if (got < event_header_bytes) {
    done_ = true;
    pos_ = size_;
    return problem(fmt::format("the log ends inside an event header at offset {} ({} of {} bytes; truncated "
                               "after event {})",
                               at, got, event_header_bytes, events_));
  }
  const std::int32_t channel_len = static_cast<std::int32_t>(be32(h + 20));
  const std::int32_t data_len = static_cast<std::int32_t>(be32(h + 24));
  if (channel_len <= 0 || channel_len >= max_channel_bytes || data_len < 0) {
    pos_ = at + 1;
    return problem(fmt::format("damaged event header at offset {} (channel length {}, data length {}) after event "
                               "{}; looking for the next event",
                               at, channel_len, data_len, events_));
  }
  const std::int64_t left = size_ - at - event_header_bytes;
  const std::int64_t end = at + event_header_bytes + channel_len + data_len;
  if (end > size_) {
    // Truncated (the logger stopped mid-write) or a damaged length: look for a later event.
    const unsigned char* p = nullptr;
    const std::int64_t have = fill(event_header_bytes + std::min<std::int64_t>(channel_len, std::max<std::int64_t>(left, 0)), &p);
    const std::string channel(reinterpret_cast<const char*>(p) + std::min(have, event_header_bytes),
                              static_cast<std::size_t>(std::max<std::int64_t>(have - event_header_bytes, 0)));
    const std::int64_t resume = find_marker(at + 1);
    if (resume < 0) {
      done_ = true;
      pos_ = size_;
    } else {
      pos_ = resume;
    }
    return problem(fmt::format("event {} at offset {} (channel {}) needs {} bytes but the log has {} left: "
                               "truncated or damaged{}",
                               events_ + 1, at, printable(channel), std::int64_t(channel_len) + data_len, left,
                               resume >= 0 ? fmt::format("; skipped to the next event at offset {}", resume)
                                           : std::string("; it is the last one and is lost")));
  }
  const unsigned char* p = nullptr;
  const std::int64_t have = fill(end - at, &p);
  if (have < end - at) {  // a read error inside the event
    done_ = true;
    return problem(fmt::format("{} inside event {} at offset {}; the rest of the log is not read", read_error_,
                               events_ + 1, at));
  }
  accept(event, p, channel_len, data_len);
  return true;
}

[[gnu::always_inline]] inline void LcmLogReader::decode(LcmLogEvent& event, const ChannelInfo& info, const void* data,
                                                      std::int32_t size) {
  event.data = data;
  event.data_size = size;
  event.channel_id = info.id;
  event.kind = LcmLogEvent::Kind::other;
  event.bench = info.bench;
  if (info.bench.empty()) return;
  if (info.kind == 1) {
    if (view_samples_message(event.samples_view, data, size)) {  // nearly always: no words needed
      if (samples_ == LcmSamples::view_and_message) samples_from_view(event.samples_view, event.samples);
      event.kind = LcmLogEvent::Kind::samples;
      return;
    }
    recheck_samples(event, data, size);
  } else if (info.kind == 2) {
    std::string why;
    if (decode_message(event.config, data, size, &why)) {
      event.kind = LcmLogEvent::Kind::config;
      return;
    }
    event.kind = LcmLogEvent::Kind::problem;
    event.problem = fmt::format("event {} on {}: {}; skipped", event.number, event.channel, why);
  }
}

// A SAMPLE message that view_samples_message turned down, checked again by the worded check, which
// is the reference: the problem in its words, or the message taken should the two ever disagree
// (never a good message skipped with an empty reason).
void LcmLogReader::recheck_samples(LcmLogEvent& event, const void* data, std::int32_t size) {
  std::string why;
  if (view_samples_message_worded(event.samples_view, data, size, &why)) {
    if (samples_ == LcmSamples::view_and_message) samples_from_view(event.samples_view, event.samples);
    event.kind = LcmLogEvent::Kind::samples;
    return;
  }
  event.kind = LcmLogEvent::Kind::problem;
  event.problem = fmt::format("event {} on {}: {}; skipped", event.number, event.channel, why);
}

// ---------------------------------------------------------------------------------------------
// read_lcm_log

bool LcmLogOptions::is_valid(std::string* why) const {
  if (max_event_reports == 0) {
    if (why) *why = "max_event_reports must be at least 1";
    return false;
  }
  return true;
}

bool LcmLogContents::has_errors() const {
  return std::any_of(diagnostics.begin(), diagnostics.end(),
                     [](const Diagnostic& d) { return d.severity == Diagnostic::Severity::error; }) ||
         std::any_of(benches.begin(), benches.end(), [](const BenchLog& b) { return b.recording.has_errors(); });
}

namespace {

struct BenchState {
  BenchState(std::string bench, const std::string& path, std::size_t max_reports, const SampleStreamOptions& o)
      : reporter(log.recording, max_reports) {
    log.bench = std::move(bench);
    log.recording.source = fmt::format("{} SPINDOWN.{}.SAMPLE", path, log.bench);
    stream.options = o;
  }
  BenchLog log;
  text::LineReporter reporter;
  SampleStream stream;
  bool bench_field_warned = false;
  std::int64_t first_event = 0, last_event = 0;
  std::size_t skipped_messages = 0;
};

void take_samples(BenchState& st, const LcmLogEvent& ev) {
  const samples_t& m = ev.samples;
  Recording& rec = st.log.recording;
  ++st.log.sample_messages;
  if (st.first_event == 0) st.first_event = ev.number;
  st.last_event = ev.number;
  if (m.bench != st.log.bench && !st.bench_field_warned) {
    st.bench_field_warned = true;
    st.reporter.warn(ev.number, fmt::format("message names bench {} but came on {}; the channel's bench is used",
                                            printable(m.bench), ev.channel));
  }
  struct Sink {
    BenchState& st;
    Recording& rec;
    std::int64_t event;
    void problem(SampleProblem kind, std::int64_t count, std::string text) {
      switch (kind) {
        case SampleProblem::samples_lost: st.log.samples_lost += count; break;
        case SampleProblem::unknown_quantity:
        case SampleProblem::quantity_change:
        case SampleProblem::repeated: ++st.skipped_messages; break;
        case SampleProblem::sequence_restart: st.reporter.report(Diagnostic::Severity::note, event, text); return;
        case SampleProblem::new_source: ++st.log.new_sources; [[fallthrough]];
        case SampleProblem::clock_restart:
          if (!rec.empty() && (rec.clock_restarts.empty() || rec.clock_restarts.back() != rec.size()))
            rec.clock_restarts.push_back(rec.size());
          st.reporter.report(Diagnostic::Severity::note, event, text);
          return;
        case SampleProblem::two_sources:
          st.reporter.warn(event, fmt::format("SPINDOWN.{}.SAMPLE {}", st.log.bench, text));
          return;
        case SampleProblem::other_source:
        case SampleProblem::jump:
        case SampleProblem::late: break;
        case SampleProblem::bad_value:
        case SampleProblem::time_backwards: break;
      }
      st.reporter.warn(event, text);
    }
    void sample(std::int64_t, std::int64_t t_us, double v) { rec.push(static_cast<double>(t_us) / 1e6, v); }
    void origin(std::int64_t e) { event = e; }  // a message that waited past a gap: its own event
  };
  st.stream.take(m, static_cast<std::size_t>(std::max(m.n, 0)), ev.log_utime, Sink{st, rec, ev.number}, ev.number);
  if (st.stream.quantity_known) rec.quantity = st.stream.quantity;
}

// The end of the log: what the stream still holds (sample_stream.hpp flush).
void flush_samples(BenchState& st) {
  Recording& rec = st.log.recording;
  struct Sink {
    BenchState& st;
    Recording& rec;
    std::int64_t event;
    void problem(SampleProblem kind, std::int64_t count, std::string text) {
      if (kind == SampleProblem::samples_lost) st.log.samples_lost += count;
      if (kind == SampleProblem::clock_restart && !rec.empty() &&
          (rec.clock_restarts.empty() || rec.clock_restarts.back() != rec.size()))
        rec.clock_restarts.push_back(rec.size());
      st.reporter.warn(event, text);
    }
    void sample(std::int64_t, std::int64_t t_us, double v) { rec.push(static_cast<double>(t_us) / 1e6, v); }
    void origin(std::int64_t e) { event = e; }
  };
  st.stream.flush(Sink{st, rec, st.last_event});
}

void take_config(BenchState& st, const LcmLogEvent& ev) {
  const config_t& c = ev.config;
  ++st.log.config_messages;
  if (c.bench != st.log.bench)
    st.reporter.warn(ev.number, fmt::format("config names bench {} but came on {}; the channel's bench is used",
                                            printable(c.bench), ev.channel));
  if (st.log.config && (st.log.config->inertia_kg_m2 != c.inertia_kg_m2 ||
                        st.log.config->kb_v_s_per_rad != c.kb_v_s_per_rad)) {
    st.reporter.report(Diagnostic::Severity::note, ev.number,
                       fmt::format("bench parameters change: J {} -> {} kg·m², K_b {} -> {} V·s/rad; the latest is "
                                   "used",
                                   st.log.config->inertia_kg_m2, c.inertia_kg_m2, st.log.config->kb_v_s_per_rad,
                                   c.kb_v_s_per_rad));
  }
  st.log.config = c;
}

}  // namespace

LcmLogContents read_lcm_log(const std::string& path, const LcmLogOptions& options) {
  LcmLogContents out;
  out.path = path;
  std::string why;
  if (!options.is_valid(&why)) {
    out.diagnostics.push_back({Diagnostic::Severity::error, path, 0, "invalid reader options: " + why});
    return out;
  }
  LcmLogReader reader(path);
  if (!reader.good()) {
    out.diagnostics.push_back({Diagnostic::Severity::error, path, 0, reader.open_error()});
    return out;
  }
  std::vector<std::unique_ptr<BenchState>> benches;
  auto bench = [&](std::string_view id) -> BenchState& {
    for (auto& b : benches)
      if (b->log.bench == id) return *b;
    benches.push_back(std::make_unique<BenchState>(std::string(id), path, options.max_event_reports, options.stream));
    return *benches.back();
  };
  MessageGate gate(options.gate);
  // The gate's verdict on a SAMPLE or CONFIG event; a refused one is named on its bench.
  auto admitted = [&](const LcmLogEvent& e, std::string_view lab, std::string_view sent_to) {
    if (gate.accepts_at_once(lab, sent_to)) return true;
    const GateResult g = gate.check(e.channel, e.data, e.data_size, e.log_utime);
    if (!g.refused()) return true;
    BenchState& st = bench(e.bench);
    ++st.log.refused_messages;
    if (e.channel.ends_with(".SAMPLE")) ++st.skipped_messages, ++st.log.sample_messages;
    st.reporter.warn(e.number, g.text);
    return false;
  };
  std::size_t file_problems = 0;
  LcmLogEvent ev;
  while (reader.next(ev)) {
    switch (ev.kind) {
      case LcmLogEvent::Kind::samples:
        if (admitted(ev, ev.samples_view.lab, ev.samples_view.sent_to)) take_samples(bench(ev.bench), ev);
        break;
      case LcmLogEvent::Kind::config:
        if (admitted(ev, ev.config.lab, ev.config.sent_to)) take_config(bench(ev.bench), ev);
        break;
      case LcmLogEvent::Kind::other: ++out.other_channels[std::string(ev.channel)]; break;
      case LcmLogEvent::Kind::problem:
        if (!ev.bench.empty() && ev.number > 0) {
          BenchState& st = bench(ev.bench);
          if (ev.channel.ends_with(".SAMPLE")) ++st.skipped_messages, ++st.log.sample_messages;
          st.reporter.warn(ev.number, ev.problem);
        } else if (++file_problems <= options.max_event_reports) {
          out.diagnostics.push_back({Diagnostic::Severity::warning, path, ev.number, ev.problem});
        }
        break;
    }
  }
  out.events = reader.events_read();
  if (file_problems > options.max_event_reports)
    out.diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                               fmt::format("{} more damaged parts of the file not listed; {} in all",
                                           file_problems - options.max_event_reports, file_problems)});

  for (auto& b : benches) {
    flush_samples(*b);
    b->reporter.finish();
    Recording& rec = b->log.recording;
    rec.lines_read = static_cast<std::size_t>(b->log.sample_messages);
    rec.lines_skipped = b->skipped_messages;
    if (b->log.sample_messages == 0) {
      rec.note(0, fmt::format("bench {}: {} config messages, no samples", b->log.bench, b->log.config_messages));
    } else if (rec.empty()) {
      rec.error(0, fmt::format("no samples: {} messages on {} (events {} to {}), none with a usable sample",
                               b->log.sample_messages, rec.source.substr(path.size() + 1), b->first_event,
                               b->last_event));
    } else {
      rec.note(0, fmt::format("{} samples ({}) from {} messages (events {} to {}){}{}", rec.size(),
                              quantity_unit(rec.quantity), b->log.sample_messages, b->first_event, b->last_event,
                              b->log.samples_lost ? fmt::format(", {} lost in sequence gaps", b->log.samples_lost)
                                                  : std::string(),
                              b->log.config ? std::string() : std::string(", no config message")));
    }
    out.benches.push_back(std::move(b->log));
  }
  return out;
}

}  // namespace spindown
