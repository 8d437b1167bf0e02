#pragma once
// The lab as spindown-web shows it: fed the decoded LCM messages of every bench (SAMPLE, CONFIG,
// STATUS, RUN, FIT, EXPLAIN) and the services' heartbeats, it keeps
//   - `spindown watch`'s table (LabTable: run state, last fit, bridge health, services),
//   - per bench: each run's samples (RunTrace: full resolution up to a cap for the CSV, thinned to
//     at most max_display_points for the pages), the cut and stop, the FIT (its numbers exactly,
//     each model's curve, the best model's residuals), the EXPLAIN story; the last runs_kept runs,
//   - and turns them into JSON: the /api/state snapshot, a page's first view (snapshot()), and
//     the changes since the last take_updates() as Server-Sent Events.
//
// Not thread-safe: the service calls it under one mutex (from LCM's thread and the HTTP
// threads). Bounded: max_benches benches (LabTable's rule: the least recently heard goes),
// runs_kept runs per bench, max_run_samples samples per run, lead_samples samples between runs.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/explain_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/bench_state.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/lab_table.hpp"
#include "spindown/run_trace.hpp"
#include "spindown/sample_stream.hpp"

namespace spindown {

struct WebLabOptions {
  double silent_after_s = 5.0;          // a bench without samples this long is silent
  std::size_t max_benches = 64;
  std::size_t runs_kept = 8;            // per bench, the current run included
  std::size_t max_run_samples = 30000;  // per run at full resolution (10 min at 50 Hz)
  std::size_t max_display_points = 2000;
  std::size_t curve_points = 200;       // per model curve on the bench page
  std::size_t tile_points = 400;        // per bench in a room page's first view
  double preroll_s = 2.0;               // seconds before the cut a run's trace starts
  std::size_t lead_samples = 1000;      // samples kept between runs (for the next run's preroll)
  bool lab_units = true;                // coefficients' text in g·cm² units (SI otherwise)
  std::string lab_name;                 // the lab's name (--lab), on the pages and the printed record
  bool signatures_checked = false;      // the messages passed a gate with the lab key (a signed fit is the lab's)
  std::vector<std::string> expected_benches;  // shown from the start (bench files), silent until heard
  bool is_valid(std::string* why) const;
};

// One run of one bench.
struct WebRun {
  WebRun(std::size_t max_samples, std::size_t max_display) : trace(max_samples, max_display) {}
  std::int32_t number = 0;  // the fitter's run number
  std::int64_t key = 0;     // unique per bench in this service's life: the pages tell runs apart by it
  bool partial = false;     // the cut was not seen
  std::int8_t state = run_t::STATE_COASTING;
  double t_cut_s = std::numeric_limits<double>::quiet_NaN();  // device time; NaN while unknown
  double t_stop_s = std::numeric_limits<double>::quiet_NaN();
  std::string note;
  bool open = true;         // still taking samples (until its FIT, or abandoned)
  RunTrace trace;
  Json fit;                 // fit_summary_json, or null
  Json curves;              // fit_curves_json, or null
  Json explain;             // explain_json, or null
  double x0() const;        // the plots' zero: the cut, else the first sample
};

// The changes since the last take_updates(), as Server-Sent Events ("event: NAME\ndata: JSON\n\n").
struct WebUpdate {
  enum class To { everyone, room, bench, room_and_bench };
  To to = To::everyone;
  std::string bench;  // for To::bench, To::room_and_bench
  std::shared_ptr<const std::string> event;
};

// "event: NAME\ndata: JSON\n\n" (the JSON on one line).
std::string sse_event(std::string_view name, const Json& data);

class WebLab {
 public:
  explicit WebLab(WebLabOptions options = {});

  // Decoded messages; bench is the bench id of the channel (status: the channel's id, a bench or
  // a service instance), now_us the host time they arrived.
  void on_samples(std::string_view bench, const samples_t& msg, std::int64_t now_us);
  void on_config(std::string_view bench, const config_t& msg, std::int64_t now_us);
  void on_status(std::string_view channel_id, const status_t& msg, std::int64_t now_us);
  void on_run(std::string_view bench, const run_t& msg, std::int64_t now_us);
  void on_fit(std::string_view bench, const fit_t& msg, std::int64_t now_us);
  void on_explain(std::string_view bench, const explain_t& msg, std::int64_t now_us);
  // A message that did not decode, or that the bench's handler refused (its words).
  void on_bad_message(std::string text, std::int64_t now_us);
  // A message refused before decoding (signature, lab): never shown as data; counted and named.
  // bench: a refused SAMPLE's bench: unless another lab's, its tile says it is refused, and why.
  // bench: a refused sample's bench (a tile for it, its state); about: the bench another refused
  // message names (a FIT, a RUN …): said on that bench's tile if it has one, never a new tile.
  void on_refused(const GateResult& refused, std::int64_t now_us, std::string_view bench = {},
                  std::string_view about = {});

  // GET /api/state: {"benches":[summary…],"lab":{…}}; summaries with their counters.
  Json state_json(std::int64_t now_us) const;
  // GET /api/bench/<id>: {"bench":summary,"detail":…,"samples":…}; nullopt for an unknown bench.
  std::optional<Json> bench_json(std::string_view id, std::int64_t now_us) const;
  // GET /api/bench/<id>/runs/<n>: one kept run (points, fit, curves); nullopt when not kept.
  std::optional<Json> run_json(std::string_view id, std::int32_t number) const;
  // GET /bench/<id>/runs/<n>.csv: the run's samples; nullopt when not kept.
  std::optional<std::string> run_csv(std::string_view id, std::int32_t number) const;
  bool knows(std::string_view id) const;

  // A page's first view, as the "snapshot" event: bench "" for the room page (every bench, each
  // trace thinned to tile_points), else that bench's page (its summary, detail and whole trace).
  std::string snapshot_event(std::string_view bench, std::int64_t now_us) const;

  // What changed since the last call (states that changed with time included): summaries of
  // benches whose shown state changed, new samples of each bench's current run, run details
  // (markers, fit, curves, residuals, explain, earlier runs), the list of benches, the services.
  std::vector<WebUpdate> take_updates(std::int64_t now_us);

  const LabTable& table() const { return table_; }
  const WebLabOptions& options() const { return opt_; }
  std::size_t bench_count() const { return benches_.size(); }
  std::int64_t refused_messages() const { return refused_; }
  std::int64_t bad_messages() const { return table_.bad_messages(); }

 private:
  struct Bench {
    std::string id;
    bool expected = false;
    std::string refused_other;     // the last refused message naming it that was not a sample
    std::int64_t refused_other_us = 0;
    BenchActivity activity;
    SampleStream stream;
    std::deque<TracePoint> lead;  // samples while no run is open (the next run's preroll)
    std::deque<WebRun> runs;      // oldest first; back() is the current run
    std::int64_t next_key = 1;
    Json last_fit = nullptr;      // the room tile's headline FIT summary, even of a run no longer kept: the
                                  // latest whole run's (whole_run()), else the latest of any
    bool last_fit_whole = false;  // the headline is a whole run's
    Json last_fit_curve = Json::array();
    // What the pages were last sent.
    std::string sent_summary;
    std::int64_t sent_key = 0;
    std::size_t sent_points = 0, sent_stride = 0;
    std::int64_t sent_received = 0;
    double sent_live = 0;
    bool detail_changed = true;
  };

  Bench* find(std::string_view id);
  const Bench* find(std::string_view id) const;
  Bench& bench(std::string_view id);
  void forget_dropped_rows();
  WebRun* run_of(Bench& b, std::int32_t number, double t_cut_s);
  WebRun& start_run(Bench& b, std::int32_t number, double t_cut_s);
  void close_run(Bench& b, WebRun& r);

  Json summary_json(const Bench& b, std::int64_t now_us, bool counters) const;
  Json run_summary_json(const Bench& b, const WebRun& r, bool counts = true) const;
  Json detail_json(const Bench& b) const;
  Json points_json(const Bench& b, std::size_t first, std::size_t step, bool reset) const;
  Json lab_json(std::int64_t now_us) const;
  std::vector<const Bench*> ordered() const;

  WebLabOptions opt_;
  LabTable table_;
  std::map<std::string, Bench, std::less<>> benches_;
  std::int64_t forgotten_seen_ = 0;
  std::int64_t refused_ = 0;
  std::string last_refused_;
  std::string sent_roster_, sent_lab_;
};

}  // namespace spindown
