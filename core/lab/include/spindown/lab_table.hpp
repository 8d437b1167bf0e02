#pragma once
// The state behind `spindown watch`: one row per bench (its run's state from RUN, its last fit
// from FIT, its bridge's health from STATUS, sequence gaps seen on SAMPLE, the age of its last
// message) and one row per service (fitter, logger: state and key counters). Fed decoded
// messages with the host time they arrived; renders a plain-text table and short event lines
// ("bench-a: run 2 fit: combined …"), so it is testable without a terminal or LCM.
//
// Bounded: at most max_benches benches and max_services services (the least recently heard
// is forgotten, and counted), a fixed number of recent events.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/message_gate.hpp"
#include "spindown/sample_stream.hpp"
#include "spindown/service_instances.hpp"
#include "spindown/utf8_text.hpp"  // display_width: the columns this table's text takes

namespace spindown {

struct LabTableOptions {
  bool lab_units = false;          // coefficients in the lab's g·cm² units (SI otherwise)
  double stale_s = 5.0;            // a row whose last message is older is marked stale ("!")
  std::size_t max_benches = 64;    // rows kept; more forgets the least recently heard
  std::size_t max_services = 16;
  std::size_t max_events = 200;    // events not yet taken; older ones are dropped (and counted)
  double gap_event_every_s = 10.0; // sequence-gap events at most this often per bench
  bool signatures_checked = false; // messages pass a gate with the lab key first (watch --key)
  SampleStreamOptions stream;      // a bench's SAMPLE sources, as the fitter follows them
  // A run shown coasting (or at a provisional stop) is no longer followed once no fitter has
  // sent a heartbeat for this long (or the last one said "stopping") and its last RUN is as old:
  // the row says "not followed (no fitter for N s)" instead of "coasting" for ever.
  double fitter_lost_s = 10.0;
};

// What the table knows about one bench.
struct LabBenchRow {
  std::string bench;
  std::int64_t last_message_us = 0;  // host time of the bench's last message (any channel)

  // From SPINDOWN.<bench>.RUN.
  bool has_run = false;
  std::int32_t run = 0;
  std::int8_t run_state = run_t::STATE_POWERED;
  double t_cut_s = 0, t_stop_s = 0;
  std::int32_t run_samples = 0;
  bool run_partial = false;          // the cut was not seen (joined mid-coast)
  std::int64_t last_run_us = 0;      // host time of the last RUN

  // From SPINDOWN.<bench>.FIT: the latest fit.
  bool has_fit = false;
  std::int32_t fit_run = 0;
  bool fit_partial = false;          // fitted from its first sample: the cut was not seen
  std::string fit_end;               // why the fitted window ends ("stopped", "cap", "clock restart", …)
  std::string fit_doubt;             // why this fit may not be the lab fitter's ("" when nothing says so)
  std::int32_t fits = 0;             // FIT messages seen
  std::string best;                  // best model ("" when none converged)
  std::string coefficients;          // the best model's friction coefficients ± error (no units)
  double rmse = 0;
  std::string residual_unit;
  // The combined model's c3 and c4 with their total standard errors (J's and K_b's uncertainty
  // included), in SI or the lab's units as the table shows them; NaN when it has none.
  double c3 = 0, c3_error = 0, c4 = 0, c4_error = 0;
  std::string bench_source;          // "config" or why a default J/K_b was used
  std::string health;                // motor health verdict "ok"/"check"/"service" ("" when not assessed)
  std::string health_reason;         // its reason in words

  // From the bridge's SPINDOWN.<bench>.STATUS.
  bool has_bridge = false;
  std::string bridge_state;          // "connected", "disconnected", …
  std::int64_t lines_good = 0, lines_bad = 0;
  double rate_hz = 0;
  std::string bridge_error;

  // From SPINDOWN.<bench>.SAMPLE, as this listener saw it: the stream as the fitter follows it
  // (sample_stream.hpp: its source, gaps, a new source, two at once).
  bool has_samples = false;
  SampleStream stream;
  std::int64_t samples = 0;
  std::int64_t sample_messages = 0;
  std::int64_t seq_gaps = 0;         // gaps in samples_t.seq
  std::int64_t samples_missing = 0;  // samples in those gaps
  std::int64_t seq_restarts = 0;     // a new source took over (bridge restarted, board replugged)
  std::int64_t other_source_samples = 0;  // samples of a second source, not the stream's
  std::int64_t seq_jumps = 0;        // messages that jumped far from the stream and were dropped
  std::string two_sources;           // the latest "has two sources: …" ("" never)
  std::int64_t last_sample_us = 0;   // host time of its last SAMPLE the gate let through
  // Its SAMPLEs the gate refused (unsigned, another key, a replay; never another lab's): the
  // latest reason, its kind and when. Shown as the row's state while no sample is let through.
  std::string refused, refused_kind;
  std::int64_t refused_us = 0;
  std::int64_t other_source_us = 0;  // when a second source was last heard
  std::int64_t last_gap_event_us = 0;
  std::int64_t gaps_at_last_event = 0;

  bool has_config = false;
};

// A service's heartbeat (fitter, logger, …), keyed by service and instance.
struct LabServiceRow {
  LabServiceRow(const std::string& service_name, const std::string& instance_name)
      : instances(service_name, instance_name) {}
  std::string service, instance, host, state, last_error;
  std::int32_t pid = 0;
  double uptime_s = 0;
  std::vector<std::pair<std::string, std::int64_t>> counters;  // the ones worth showing
  std::int64_t last_message_us = 0;
  ServiceInstances instances;        // every process heard under this name (two at once: named)
  std::string collision;             // the latest "two …s with the same instance name …" ("" never)
};

class LabTable {
 public:
  explicit LabTable(LabTableOptions options = {});

  // Decoded messages; bench is the bench id of the channel they came on, now_us the host
  // time they arrived (µs since the epoch).
  void on_samples(std::string_view bench, const samples_t& msg, std::int64_t now_us);
  // Time passes: sequence gaps that waited long enough for late datagrams are counted lost.
  void tick(std::int64_t now_us);
  void on_config(std::string_view bench, const config_t& msg, std::int64_t now_us);
  void on_run(std::string_view bench, const run_t& msg, std::int64_t now_us);
  void on_fit(std::string_view bench, const fit_t& msg, std::int64_t now_us);
  // A bridge's status (service "bridge") goes to its bench's row, any other to a service row.
  void on_status(std::string_view channel_id, const status_t& msg, std::int64_t now_us);
  // A message that could not be decoded (counted, the text kept for the footer).
  void on_bad_message(std::string text, std::int64_t now_us);
  // A message the gate refused (another lab's; with the key, unsigned, wrongly signed, replayed):
  // never shown as data; counted, the first of each kind an event, the latest in the footer.
  // bench: the bench of a refused SAMPLE ("" for other channels): unless it is another lab's, the
  // bench gets a row that says its samples are refused and why (a key changed on one PC).
  void on_refused(const GateResult& refused, std::int64_t now_us, std::string_view bench = {});

  // Whether row's open run is no longer followed by a fitter at now_us (fitter_lost_s).
  bool run_unfollowed(const LabBenchRow& row, std::int64_t now_us) const;
  // Whether row's samples are being refused now: refused within stale_s, none let through since.
  bool refused_now(const LabBenchRow& row, std::int64_t now_us) const;
  // The table at now_us. width > 0 fits it to that many columns (a terminal's width): one row per
  // bench with its run, the last fit's model, the combined model's c3 and c4 with their errors and
  // the health verdict always; headers and cells shortened first, then the columns worth least
  // dropped one by one (bridge, sequence gaps, RMSE, age, last fit), and only then lines cut.
  std::string render(std::int64_t now_us, std::size_t width = 0) const;
  // Events since the last call, oldest first, without time stamps ("bench-a: run 2 coasting…").
  std::vector<std::string> take_events();

  // True when something shown changed since clear_changed() (plain output prints only then).
  bool changed() const { return changed_; }
  void clear_changed() { changed_ = false; }

  const LabBenchRow* bench(std::string_view id) const;
  std::vector<std::string> bench_ids() const;  // sorted
  std::size_t bench_count() const { return benches_.size(); }
  const LabServiceRow* service(std::string_view service, std::string_view instance) const;
  std::size_t service_count() const { return services_.size(); }
  std::vector<const LabServiceRow*> services() const;  // sorted by service, then instance
  std::int64_t bad_messages() const { return bad_messages_; }
  std::int64_t refused_messages() const { return refused_; }
  std::int64_t forgotten_rows() const { return forgotten_rows_; }
  std::int64_t dropped_events() const { return dropped_events_; }

 private:
  LabBenchRow& row(std::string_view bench, std::int64_t now_us);
  std::string bench_table(std::int64_t now_us, std::size_t width) const;  // the rows and their units line
  bool two_sources_now(const LabBenchRow& r, std::int64_t now_us) const;  // a second SAMPLE source heard lately
  void event(std::string text);

  LabTableOptions opt_;
  std::map<std::string, LabBenchRow, std::less<>> benches_;
  struct StreamSink;  // a bench's SampleStream words -> its row and the events
  void gap_event(LabBenchRow& r, std::int64_t now_us);
  std::map<std::string, LabServiceRow, std::less<>> services_;  // "service/instance"
  std::int64_t last_fitter_us_ = 0;  // the newest heartbeat of any fitter
  bool fitter_stopping_ = false;     // that heartbeat said "stopping"
  std::deque<std::string> events_;
  std::int64_t bad_messages_ = 0;
  std::string last_bad_message_;
  std::int64_t refused_ = 0;
  std::map<std::string, std::int64_t, std::less<>> refused_by_kind_;  // gate_verdict_name -> count
  std::set<std::string> refused_said_;                                // "kind channel" said as an event
  std::string last_refused_;
  std::vector<std::uint64_t> fitter_sessions_;  // sessions of every fitter heard on STATUS (bounded)
  bool signed_traffic_ = false;                 // a signed message seen (matters when not checked)
  std::int64_t forgotten_rows_ = 0;
  std::int64_t dropped_events_ = 0;
  bool changed_ = false;
};

// The best model's friction coefficients of a fit message, "c3 = 1.822 ± 0.011 g·cm²·s⁻¹, …"
// (lab units) or in SI, units left out when with_units is false; "" when the message names no
// usable best model.
std::string fit_coefficients_text(const fit_t& msg, bool lab_units, bool with_units = true);

// A line cut to width code points (never inside a character); width 0 leaves it whole.
std::string cut_to_width(const std::string& line, std::size_t width);

}  // namespace spindown
