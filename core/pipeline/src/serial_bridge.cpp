#include "spindown/serial_bridge.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <unistd.h>

#include "spindown/clock.hpp"
#include "spindown/host_name.hpp"
#include "spindown/lab_line.hpp"
#include "spindown/lcm_status.hpp"
#include "spindown/text_repairs.hpp"

namespace spindown {

namespace {

// A line as it can be shown in a status message: at most max bytes, non-printables escaped.
std::string printable(std::string_view text, std::size_t max = 60) {
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\t') out += "\\t";
    else if (c == '\\') out += "\\\\";
    else if (c == '"') out += "\\\"";
    else if (c < 0x20 || c >= 0x7f) out += fmt::format("\\x{:02x}", c);
    else out += static_cast<char>(c);
  }
  if (text.size() > max) out += "...";
  return out;
}

std::int8_t to_lcm_quantity(Quantity q) {
  switch (q) {
    case Quantity::back_emf_volts: return samples_t::QUANTITY_BACK_EMF_V;
    case Quantity::rpm: return samples_t::QUANTITY_RPM;
    case Quantity::rad_per_s: return samples_t::QUANTITY_RAD_S;
  }
  return samples_t::QUANTITY_BACK_EMF_V;
}

// Samples before any banner are converted with the protocol's defaults.
const SpindownBanner default_banner{};

}  // namespace

std::string_view wire_protocol_name(WireProtocol p) {
  switch (p) {
    case WireProtocol::unknown: return "unknown";
    case WireProtocol::lab: return "lab-tsv";
    case WireProtocol::spindown_v1: return spindown_protocol_name;
  }
  return "unknown";
}

SerialBridge::SerialBridge(BridgeSettings settings, BridgeSink& sink)
    : s_(std::move(settings)), sink_(sink), splitter_(s_.max_line_bytes) {
  if (s_.host.empty()) s_.host = host_name();
  if (s_.pid == 0) s_.pid = static_cast<int>(::getpid());
  batch_.bench = s_.bench;
  batch_.n = 0;
}

void SerialBridge::start(std::int64_t now_us) {
  start_us_ = now_us;
  rate_window_start_us_ = now_us;
  next_status_us_ = now_us;
  next_config_us_ = now_us;
  tick(now_us);
}

void SerialBridge::connected(std::int64_t now_us) {
  if (ever_connected_) ++counters_.reconnects;
  ever_connected_ = true;
  connected_ = true;
  forget_wrong_baud();
  state_ = "connected";
  // The device is there again: its error is over (the heartbeat and the pages stop showing
  // "cannot open"; the logs and stderr keep it). Other errors stay until replaced.
  if (device_error_) last_error_.clear(), last_error_utime_ = 0, device_error_ = false;
  next_status_us_ = now_us;  // say so now, not at the next heartbeat
  tick(now_us);
}

void SerialBridge::disconnected(std::int64_t now_us, std::string_view why) {
  flush();
  if (splitter_.reset() > 0) ++counters_.partial_lines;
  if (connected_) ++counters_.disconnects;
  connected_ = false;
  forget_wrong_baud();
  state_ = "disconnected";
  error(std::string(why), now_us);
  device_error_ = true;
  next_status_us_ = now_us;
  tick(now_us);
}

void SerialBridge::open_failed(std::int64_t now_us, std::string_view why) {
  ++counters_.open_failures;
  connected_ = false;
  if (state_ != "disconnected") {
    state_ = "disconnected";
    next_status_us_ = now_us;
  }
  error(std::string(why), now_us);
  device_error_ = true;
  tick(now_us);
}

void SerialBridge::error(std::string text, std::int64_t now_us) {
  last_error_ = std::move(text);
  last_error_utime_ = now_us;
  device_error_ = false;
}

void SerialBridge::feed(std::string_view bytes, std::int64_t now_us) {
  feed_start_ns_ = monotonic_ns();
  counters_.bytes += static_cast<std::int64_t>(bytes.size());
  bytes_since_good_ += static_cast<std::int64_t>(bytes.size());
  for (const char ch : bytes) {
    const auto c = static_cast<unsigned char>(ch);
    if (!(c == '\t' || c == '\r' || c == '\n' || (c >= 0x20 && c < 0x7f))) ++nontext_since_good_;
  }
  splitter_.feed(bytes, [&](const LineSplitter::Line& line) { on_line(line, now_us); });
  flush();
  check_wrong_baud(now_us);
}

void SerialBridge::good_line(std::int64_t now_us) {
  ++counters_.lines_good;
  bytes_since_good_ = 0;
  nontext_since_good_ = 0;
  if (!wrong_baud_) return;
  forget_wrong_baud();
  if (connected_) state_ = "connected";
  next_status_us_ = now_us;  // say so now
}

void SerialBridge::forget_wrong_baud() {
  wrong_baud_ = false;
  bytes_since_good_ = 0;
  nontext_since_good_ = 0;
}

void SerialBridge::check_wrong_baud(std::int64_t now_us) {
  if (wrong_baud_ || !connected_ || bytes_since_good_ < wrong_baud_bytes || nontext_since_good_ * 4 < bytes_since_good_)
    return;
  wrong_baud_ = true;
  const char* hint = s_.baud == 9600 ? "spindown-v1 firmware uses 115200" : "the lab sketch uses 9600";
  state_ = fmt::format("no valid line in {} bytes at {} baud — wrong baud? {}", bytes_since_good_, s_.baud, hint);
  error(fmt::format("{}: {} ({}% of them not text)", s_.device, state_, 100 * nontext_since_good_ / bytes_since_good_),
        now_us);
  next_status_us_ = now_us;  // say so now
}

void SerialBridge::on_line(const LineSplitter::Line& line, std::int64_t now_us) {
  ++lines_seen_;
  if (line.oversize) {
    ++counters_.oversize_lines;
    bad_line(line.text, fmt::format("line longer than {} bytes, discarded up to its newline", s_.max_line_bytes),
             now_us);
    return;
  }
  if (looks_like_spindown_line(line.text))
    on_spindown_line(line.text, now_us);
  else
    on_lab_line(line.text, now_us);
}

void SerialBridge::bad_line(std::string_view text, std::string_view why, std::int64_t now_us, std::int64_t line_no) {
  ++counters_.lines_bad;
  error(fmt::format("{} line {}: {}: \"{}\"", s_.device, line_no < 0 ? lines_seen_ : line_no, why, printable(text)),
        now_us);
}

void SerialBridge::set_protocol(WireProtocol p, std::int64_t now_us) {
  if (p == protocol_) return;
  if (!lab_held_.empty()) release_lab_held();  // the lab's samples so far, as millis()
  if (protocol_ != WireProtocol::unknown)
    error(fmt::format("{}: protocol changed from {} to {}", s_.device, wire_protocol_name(protocol_),
                      wire_protocol_name(p)),
          now_us);
  protocol_ = p;
  flush();  // a batch holds one protocol's samples
  clock_.set_tick_us(p == WireProtocol::lab ? 1000 : 1);  // millis() vs micros(); a new epoch
  lab_clock_ = LabClock::unknown;  // the lab's columns: told by their first samples' step
  have_device_seq_ = false;
  next_config_us_ = now_us;  // the config changed: publish it with the next tick
}

void SerialBridge::on_lab_line(std::string_view text, std::int64_t now_us) {
  if (table_) [[unlikely]] {
    on_table_line(text, now_us, lines_seen_);
    return;
  }
  const LabLine l = parse_lab_line(text);
  switch (l.kind) {
    case LabLine::Kind::blank: ++counters_.lines_blank; return;
    case LabLine::Kind::garbled: hold_for_layout(text, now_us); return;
    case LabLine::Kind::sample: break;
  }
  if (!held_.empty()) [[unlikely]]
    held_.clear();  // a few lines of something else (a boot message) before the lab's lines
  good_line(now_us);
  set_protocol(WireProtocol::lab, now_us);
  if (lab_clock_ != LabClock::known) [[unlikely]] {
    lab_sample(static_cast<std::uint64_t>(l.millis), l.value, now_us);
    return;
  }
  const auto r = clock_.update(static_cast<std::uint64_t>(l.millis));
  add_sample(r, now_us, l.value, -1);
}

namespace {
// The step between two counter readings, across a 32-bit wrap.
std::uint64_t counter_step(std::uint64_t from, std::uint64_t to) { return (to - from) & 0xFFFF'FFFFull; }
bool micros_step(std::uint64_t step) { return step >= 4000 && step <= 200000; }
}  // namespace

void SerialBridge::lab_sample(std::uint64_t ticks, double value, std::int64_t now_us) {
  if (lab_clock_ == LabClock::unknown && lab_held_.empty() && ticks < 100'000'000) {
    lab_clock_ = LabClock::provisional;  // millis(), published at once; the next sample checks it
    lab_first_ticks_ = ticks;
    add_sample(clock_.update(ticks), now_us, value, -1);
    return;
  }
  if (lab_clock_ == LabClock::provisional) {
    const std::uint64_t step = counter_step(lab_first_ticks_, ticks);
    if (ticks > lab_first_ticks_ && step > 200000) {  // no clock's step forward: the first was a line cut
                                                       // short ("96" of "…664"); told anew (back: a reset)
      lab_clock_ = LabClock::unknown;
      lab_held_.push_back({ticks, value, now_us});
      return;
    }
    lab_clock_ = LabClock::known;
    if (micros_step(step)) use_micros(double(step), now_us);  // the first sample stays in its own epoch
    add_sample(clock_.update(ticks), now_us, value, -1);
    return;
  }
  lab_held_.push_back({ticks, value, now_us});
  const std::size_t n = lab_held_.size();
  if (n < 2) return;
  const std::uint64_t step = counter_step(lab_held_[n - 2].ticks, ticks);
  if (micros_step(step)) use_micros(double(step), now_us);
  if (step < 4000 || micros_step(step) || n >= 5) release_lab_held();
}

void SerialBridge::use_micros(double step, std::int64_t now_us) {
  clock_.set_tick_us(1, 1ull << 32);  // micros() wraps at 2^32 µs
  error(fmt::format("{}: the times step by ~{:.0f} from sample to sample: micros() (µs), not millis(); read as µs, "
                    "as spindown fit reads them",
                    s_.device, step),
        now_us);
}

void SerialBridge::release_lab_held() {
  lab_clock_ = LabClock::known;
  for (const HeldSample& h : lab_held_) add_sample(clock_.update(h.ticks), h.recv_us, h.value, -1);
  lab_held_.clear();
}

namespace {
// Lines that are not millis<TAB>volts held before a layout is looked for: the file reader finds a
// header, its delimiter and its columns from as many (it looks at the first 20 at most).
constexpr std::size_t layout_lines = 8;
}  // namespace

void SerialBridge::hold_for_layout(std::string_view text, std::int64_t now_us) {
  bad_line(text, parse_lab_line(text).why, now_us);  // said at once; taken back if a layout reads it
  // spindown-v1's port (its lines end in a checksum, "*3F"): a broken line of it is no table.
  if (protocol_ == WireProtocol::spindown_v1 || text.find('*') != std::string_view::npos) {
    held_.clear();
    return;
  }
  held_.push_back({std::string(text), now_us, lines_seen_});
  if (held_.size() >= layout_lines) learn_layout(now_us);
}

void SerialBridge::learn_layout(std::int64_t now_us) {
  // The Serial Plotter's labelled values ("millis:2020,volts:0.00"): read under a header of their
  // labels, as the file reader reads them (text_repairs.hpp).
  std::string labels, values;
  std::size_t labelled = 0;
  for (const HeldLine& h : held_) labelled += plotter_labels(h.text, &labels, &values);
  plotter_ = labelled * 2 > held_.size();
  std::string text = plotter_ ? labels + '\n' : std::string();
  for (const HeldLine& h : held_) (text += plotter_ && plotter_labels(h.text, nullptr, &values) ? values : h.text) += '\n';
  DelimitedLayout layout;
  const Recording rec = read_delimited_text(text, s_.device, {}, &layout);
  // A table when nearly every held line is one of its rows (a header and a units row aside):
  // boot messages and noise are reported as before.
  if (rec.has_errors() || rec.size() + 2 < held_.size()) {
    held_.clear();
    plotter_ = false;
    return;
  }
  counters_.lines_bad -= static_cast<std::int64_t>(held_.size());  // read again below, by the layout
  table_.emplace(layout);
  const double per_s = time_units_per_second(layout.time_unit);
  const bool millis = layout.time_unit == TimeUnit::ms, micros = layout.time_unit == TimeUnit::us;
  table_tick_us_ = millis ? 1000 : 1;
  table_ticks_per_unit_ = millis || micros ? 1.0 : 1e6 / per_s;
  set_protocol(WireProtocol::lab, now_us);
  // millis() and micros() wrap at 2^32 ticks; seconds from a PC's logger do not.
  clock_.set_tick_us(table_tick_us_, millis || micros ? 1ull << 32 : 1ull << 62);
  if (layout.quantity_from_header && layout.quantity != s_.quantity) {
    s_.quantity = layout.quantity;
    next_config_us_ = now_us;
  }
  std::string columns;
  for (const Diagnostic& d : rec.diagnostics)
    if (const auto at = d.message.find("time = column"); at != std::string::npos) columns = d.message.substr(at);
  error(fmt::format("{}: the lines are not millis<TAB>volts; read as spindown fit reads them: {}", s_.device, columns),
        now_us);
  // The held lines, by the layout now: its header (the lines before the first row) named the columns.
  std::vector<HeldLine> held = std::move(held_);
  held_.clear();
  bool rows = false;
  for (const HeldLine& h : held) {
    if (!rows && !plotter_ && !table_->read(h.text).ok) {
      good_line(h.recv_us);  // the header: used, it named the columns
      continue;
    }
    rows = true;
    on_table_line(h.text, h.recv_us, h.line_no);
  }
}

void SerialBridge::on_table_line(std::string_view text, std::int64_t now_us, std::int64_t line_no) {
  if (text.find_first_not_of(" \t\r") == std::string_view::npos) {
    ++counters_.lines_blank;
    return;
  }
  std::string values;
  if (plotter_ && plotter_labels(text, nullptr, &values)) text = values;
  const DelimitedRowReader::Row row = table_->read(text);
  if (!row.ok) {
    bad_line(text, row.why, now_us, line_no);
    return;
  }
  const double ticks = std::round(row.time * table_ticks_per_unit_);
  if (!(ticks >= 0) || ticks > 9.0e15) {
    bad_line(text, "time is negative or out of range", now_us, line_no);
    return;
  }
  good_line(now_us);
  const auto r = clock_.update(static_cast<std::uint64_t>(ticks));
  add_sample(r, now_us, row.value, -1);
}

void SerialBridge::on_spindown_line(std::string_view text, std::int64_t now_us) {
  const SpindownLine l = parse_spindown_line(text);
  switch (l.kind) {
    case SpindownLine::Kind::blank: ++counters_.lines_blank; return;
    case SpindownLine::Kind::garbled: bad_line(text, l.why, now_us); return;
    case SpindownLine::Kind::note: good_line(now_us); return;
    case SpindownLine::Kind::banner:
      good_line(now_us);
      set_protocol(WireProtocol::spindown_v1, now_us);
      banner_ = l.banner;
      banner_seen_ = true;
      next_config_us_ = now_us;
      tick(now_us);
      return;
    case SpindownLine::Kind::sample: break;
  }
  const SpindownBanner& conversion = banner_seen_ ? banner_ : default_banner;
  if (l.adc > conversion.max_count()) {
    bad_line(text, "ADC count above the converter's range", now_us);
    return;
  }
  good_line(now_us);
  set_protocol(WireProtocol::spindown_v1, now_us);
  const auto r = clock_.update(l.time_us);
  if (have_device_seq_ && !r.reset) {
    const std::uint32_t expected = last_device_seq_ + 1;
    if (l.seq != expected) {
      const std::uint32_t ahead = l.seq - expected;  // modulo 2^32
      const std::int64_t lost = ahead < 0x80000000u ? std::int64_t(ahead) : 1;
      counters_.device_seq_gaps += lost;
      error(fmt::format("{}: device sequence jumped from {} to {} ({} sample(s) lost on the wire)", s_.device,
                        last_device_seq_, l.seq, lost),
            now_us);
    }
  }
  have_device_seq_ = true;
  last_device_seq_ = l.seq;
  add_sample(r, now_us, conversion.volts(l.adc), l.adc);
}

void SerialBridge::add_sample(const DeviceClock::Reading& r, std::int64_t host_us, double value, std::int32_t raw) {
  if (r.reset) {
    flush();  // one clock epoch per message
    counters_.device_resets = r.epoch;
    error(fmt::format("{}: device clock restarted (Arduino reset), clock epoch {}", s_.device, r.epoch), host_us);
  }
  if (batch_.n == 0) {
    batch_.seq = next_seq_;
    batch_.clock_epoch = r.epoch;
    batch_.quantity = protocol_ == WireProtocol::spindown_v1 ? samples_t::QUANTITY_BACK_EMF_V
                                                              : to_lcm_quantity(s_.quantity);
  }
  batch_.device_time_us.push_back(r.time_us);
  batch_.host_time_us.push_back(host_us);
  batch_.value.push_back(value);
  batch_.raw_adc.push_back(raw);
  ++batch_.n;
  ++next_seq_;
  batch_.utime = host_us;
  if (static_cast<std::size_t>(batch_.n) >= s_.max_batch) flush();
}

void SerialBridge::flush() {
  if (batch_.n == 0) return;
  sink_.publish(batch_);
  const std::int64_t took_ns = monotonic_ns() - feed_start_ns_;
  latency_us_[latency_count_ % latency_us_.size()] = static_cast<float>(took_ns / 1000.0);
  ++latency_count_;
  counters_.samples += batch_.n;
  rate_window_samples_ += batch_.n;
  ++counters_.messages;
  batch_.n = 0;
  batch_.device_time_us.clear();
  batch_.host_time_us.clear();
  batch_.value.clear();
  batch_.raw_adc.clear();
}

double SerialBridge::latency_quantile_us(double p) const {
  const std::size_t n = std::min(latency_count_, latency_us_.size());
  if (n == 0) return 0;
  std::vector<float> v(latency_us_.begin(), latency_us_.begin() + static_cast<std::ptrdiff_t>(n));
  const auto k = static_cast<std::size_t>(std::clamp(p, 0.0, 1.0) * double(n - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

void SerialBridge::tick(std::int64_t now_us) {
  // A single sample of a large count and nothing for a second: millis() after a long uptime.
  if (!lab_held_.empty() && now_us - lab_held_.front().recv_us >= 1'000'000) release_lab_held();
  if (now_us >= next_config_us_) {
    sink_.publish(make_config(now_us));
    next_config_us_ = now_us + static_cast<std::int64_t>(s_.config_interval_s * 1e6);
  }
  if (now_us >= next_status_us_) {
    const std::int64_t window = now_us - rate_window_start_us_;
    if (window >= 200'000) {
      rate_hz_ = double(rate_window_samples_) * 1e6 / double(window);
      rate_window_start_us_ = now_us;
      rate_window_samples_ = 0;
    }
    sink_.publish(make_status(now_us));
    next_status_us_ = now_us + static_cast<std::int64_t>(s_.status_interval_s * 1e6);
  }
}

void SerialBridge::stop(std::int64_t now_us) {
  flush();
  stopping_ = true;
  state_ = "stopping";
  sink_.publish(make_status(now_us));
}

config_t SerialBridge::make_config(std::int64_t now_us) const {
  config_t c{};
  c.utime = now_us;
  c.bench = s_.bench;
  c.inertia_kg_m2 = s_.params.inertia_kg_m2;
  c.inertia_source = s_.params.inertia_source;
  c.kb_v_s_per_rad = s_.params.kb_v_s_per_rad;
  c.kb_source = s_.params.kb_source;
  c.inertia_rel_error = s_.params.inertia_rel_error;
  c.kb_rel_error = s_.params.kb_rel_error;
  c.protocol = std::string(wire_protocol_name(protocol_));
  c.baud = s_.baud;
  c.device = s_.device;
  c.host = s_.host;
  if (protocol_ == WireProtocol::spindown_v1) {
    c.quantity = samples_t::QUANTITY_BACK_EMF_V;
    const SpindownBanner b = banner_seen_ ? banner_ : SpindownBanner{};
    c.adc_volts_per_count = b.volts_per_count();
    c.adc_bits = b.adc_bits;
    c.firmware = banner_seen_ ? fmt::format("{} {}", b.firmware, b.version) : "spindown-v1 (no banner seen yet)";
    c.sample_period_s = banner_seen_ ? b.period_us * 1e-6 : 0.0;
  } else {
    c.quantity = to_lcm_quantity(s_.quantity);
    // The lab sketch prints volts = counts·ref/(2^bits − 1), rounded to 2 decimals.
    c.adc_volts_per_count = s_.adc_ref_v / double((1 << s_.adc_bits) - 1);
    c.adc_bits = s_.adc_bits;
    c.firmware = protocol_ == WireProtocol::lab ? "lab sketch" : "unknown (no valid line yet)";
    c.sample_period_s = s_.lab_period_s;
  }
  return c;
}

status_t SerialBridge::make_status(std::int64_t now_us) const {
  const std::pair<const char*, std::int64_t> counters[] = {
      {"lines_good", counters_.lines_good},
      {"lines_bad", counters_.lines_bad},
      {"lines_blank", counters_.lines_blank},
      {"oversize_lines", counters_.oversize_lines},
      {"samples", counters_.samples},
      {"messages", counters_.messages},
      {"seq", next_seq_},
      {"bytes", counters_.bytes},
      {"reconnects", counters_.reconnects},
      {"disconnects", counters_.disconnects},
      {"open_failures", counters_.open_failures},
      {"device_resets", counters_.device_resets},
      {"device_seq_gaps", counters_.device_seq_gaps},
      {"partial_lines", counters_.partial_lines},
  };
  const std::pair<const char*, double> gauges[] = {
      {"connected", connected_ ? 1.0 : 0.0},
      {"rate_hz", rate_hz_},
      {"clock_epoch", double(clock_.epoch())},
      {"buffered_bytes", double(splitter_.buffered())},
      {"latency_p50_us", latency_quantile_us(0.50)},
      {"latency_p99_us", latency_quantile_us(0.99)},
      {"latency_max_us", latency_quantile_us(1.0)},
  };
  return status_message(now_us,
                        {.service = "bridge",
                         .instance = s_.bench,
                         .host = s_.host,
                         .pid = s_.pid,
                         .state = state_,
                         .uptime_s = double(now_us - start_us_) * 1e-6,
                         .last_error = last_error_,
                         .last_error_utime = last_error_utime_},
                        counters, gauges);
}

}  // namespace spindown
