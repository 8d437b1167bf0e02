#pragma once
// The serial bridge's logic without any I/O: bytes from the port go in, samples_t, config_t and
// status_t messages come out through a sink. spindown-bridge wraps it with a SerialPort and LCM;
// tests and benchmarks drive it directly.
//
// Per line: "S,…" and "#…" lines are spindown-v1 (spindown_protocol.hpp), everything else is
// the lab sketch's "millis<TAB>volts" (lab_line.hpp). The protocol is detected from the lines
// themselves and may change (a reflashed board). A sketch that prints another table ("millis,volts"
// with commas, a header and three columns) is read as `spindown fit` reads its capture: the
// first lines that are not millis<TAB>volts wait until the file reader has learned their
// layout from them (read_delimited_text), then each line is read by it (DelimitedRowReader).
// Only lines that parse become samples; every other line is counted and the last one reported
// with the reason.
//
// A wrong baud rate garbles every byte: no line is ever valid and most bytes are not text. Once
// wrong_baud_bytes arrived since the last valid line and at least a quarter of them are not
// text, the state says so ("no valid line in N bytes at B baud — wrong baud? …"), in the status
// and last_error, until a valid line arrives. (A long line of text is not a baud problem.)
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/bridge_settings.hpp"
#include "spindown/delimited_text.hpp"
#include "spindown/device_clock.hpp"
#include "spindown/line_splitter.hpp"
#include "spindown/spindown_protocol.hpp"

namespace spindown {

class BridgeSink {
 public:
  virtual ~BridgeSink() = default;
  virtual void publish(const samples_t& msg) = 0;
  virtual void publish(const config_t& msg) = 0;
  virtual void publish(const status_t& msg) = 0;
};

struct BridgeCounters {
  std::int64_t bytes = 0;
  std::int64_t lines_good = 0;       // lines used: samples, banners, notes
  std::int64_t lines_bad = 0;        // lines not used as data (garbled and over-long)
  std::int64_t lines_blank = 0;      // empty lines (not bad, not data)
  std::int64_t oversize_lines = 0;   // of lines_bad, those longer than max_line_bytes
  std::int64_t samples = 0;          // samples published
  std::int64_t messages = 0;         // SAMPLE messages published
  std::int64_t reconnects = 0;       // successful opens after the first
  std::int64_t disconnects = 0;      // the device went away
  std::int64_t open_failures = 0;    // attempts to open the device that failed
  std::int64_t device_resets = 0;    // device clock restarts (= clock_epoch)
  std::int64_t device_seq_gaps = 0;  // spindown-v1 samples missing by their sequence number
  std::int64_t partial_lines = 0;    // partial lines dropped at a disconnect
};

enum class WireProtocol { unknown, lab, spindown_v1 };
std::string_view wire_protocol_name(WireProtocol p);  // "unknown", "lab-tsv", "spindown-v1"

class SerialBridge {
 public:
  // settings must be valid (BridgeSettings::is_valid); sink must outlive the bridge.
  SerialBridge(BridgeSettings settings, BridgeSink& sink);

  // Times are host µs since the Unix epoch.
  void start(std::int64_t now_us);                              // first CONFIG and STATUS
  void connected(std::int64_t now_us);                          // the port opened
  void disconnected(std::int64_t now_us, std::string_view why); // the port went away
  void open_failed(std::int64_t now_us, std::string_view why);  // an open attempt failed
  // Bytes read at now_us: complete lines are parsed and their samples published before return.
  void feed(std::string_view bytes, std::int64_t now_us);
  // Publishes STATUS and CONFIG when they are due; call at least every 100 ms.
  void tick(std::int64_t now_us);
  void stop(std::int64_t now_us);                               // last STATUS, state "stopping"

  const BridgeCounters& counters() const { return counters_; }
  WireProtocol protocol() const { return protocol_; }
  bool is_connected() const { return connected_; }
  const std::string& state() const { return state_; }
  // No valid line in wrong_baud_bytes, mostly not text (state() says what and why).
  bool looks_like_wrong_baud() const { return wrong_baud_; }
  static constexpr std::int64_t wrong_baud_bytes = 256;
  std::int64_t next_seq() const { return next_seq_; }
  const std::string& last_error() const { return last_error_; }
  std::size_t buffered_bytes() const { return splitter_.buffered(); }
  // Line-to-publish latency (µs, steady clock) of recent SAMPLE messages: p in [0, 1].
  double latency_quantile_us(double p) const;

  config_t make_config(std::int64_t now_us) const;
  status_t make_status(std::int64_t now_us) const;

 private:
  void on_line(const LineSplitter::Line& line, std::int64_t now_us);
  void on_lab_line(std::string_view text, std::int64_t now_us);
  // Lines that are not the lab's millis<TAB>volts: the first few wait while the file reader
  // (read_delimited_text, as `spindown fit` reads a capture) learns their table from them; then
  // every line is read by that layout (on_table_line), or they are reported bad as before.
  void hold_for_layout(std::string_view text, std::int64_t now_us);
  void learn_layout(std::int64_t now_us);
  void on_table_line(std::string_view text, std::int64_t now_us, std::int64_t line_no);
  void on_spindown_line(std::string_view text, std::int64_t now_us);
  void set_protocol(WireProtocol p, std::int64_t now_us);
  void add_sample(const DeviceClock::Reading& r, std::int64_t host_us, double value, std::int32_t raw);
  void flush();
  void bad_line(std::string_view text, std::string_view why, std::int64_t now_us, std::int64_t line_no = -1);
  void good_line(std::int64_t now_us);
  void check_wrong_baud(std::int64_t now_us);
  void forget_wrong_baud();
  void error(std::string text, std::int64_t now_us);

  BridgeSettings s_;
  BridgeSink& sink_;
  LineSplitter splitter_;
  DeviceClock clock_{1000};
  WireProtocol protocol_ = WireProtocol::unknown;
  SpindownBanner banner_;
  bool banner_seen_ = false;
  bool have_device_seq_ = false;
  std::uint32_t last_device_seq_ = 0;

  struct HeldLine {
    std::string text;
    std::int64_t recv_us, line_no;
  };
  std::vector<HeldLine> held_;                 // lines waiting for a layout (at most layout_lines)
  // The lab's two columns from millis() or micros()? Told by the step between samples, as the file
  // reader tells it (4000 to 200000 ticks: µs). A first sample below 10^8 ticks is taken as millis()
  // at once (the usual sketch, no delay) and checked at the second; a larger one (micros() after
  // 100 s, or millis() after 28 h) waits for the second sample, or a second.
  enum class LabClock { unknown, provisional, known };
  struct HeldSample {
    std::uint64_t ticks;
    double value;
    std::int64_t recv_us;
  };
  LabClock lab_clock_ = LabClock::unknown;
  std::uint64_t lab_first_ticks_ = 0;
  std::vector<HeldSample> lab_held_;
  void lab_sample(std::uint64_t ticks, double value, std::int64_t now_us);
  void use_micros(double step, std::int64_t now_us);
  void release_lab_held();
  std::optional<DelimitedRowReader> table_;    // the layout learned: every line is read by it
  std::int64_t table_tick_us_ = 1000;          // µs per device tick of the table's time column
  bool plotter_ = false;                       // the lines are the Serial Plotter's label:value pairs
  double table_ticks_per_unit_ = 1;

  samples_t batch_{};
  std::int64_t next_seq_ = 0;
  std::int64_t feed_start_ns_ = 0;  // steady clock at the start of the current feed()

  BridgeCounters counters_;
  bool connected_ = false;
  bool ever_connected_ = false;
  bool stopping_ = false;
  std::string state_ = "starting";
  std::string last_error_;
  std::int64_t last_error_utime_ = 0;
  bool device_error_ = false;  // last_error_ is the device's (cannot open it, it went away): over once connected
  std::int64_t lines_seen_ = 0;
  std::int64_t bytes_since_good_ = 0;    // bytes since the last valid line (or the connect)
  std::int64_t nontext_since_good_ = 0;  // of them, not printable ASCII, tab, CR or LF
  bool wrong_baud_ = false;

  std::int64_t start_us_ = 0;
  std::int64_t next_status_us_ = 0;
  std::int64_t next_config_us_ = 0;
  std::int64_t rate_window_start_us_ = 0;
  std::int64_t rate_window_samples_ = 0;
  double rate_hz_ = 0;

  std::array<float, 4096> latency_us_{};
  std::size_t latency_count_ = 0;
};

}  // namespace spindown
