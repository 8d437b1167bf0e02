#include "spindown/web_lab.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

#include "spindown/fail_why.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/fit_view.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_status.hpp"

namespace spindown {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t tile_curve_points = 60;


std::string_view unit_of(std::int8_t quantity) {
  const auto q = quantity_from_samples_code(quantity);
  return q ? quantity_unit(*q) : std::string_view("V");
}

bool same_time(double a, double b) { return (std::isnan(a) && std::isnan(b)) || std::fabs(a - b) < 1e-6; }

// What SampleStream::take hands over: the samples kept (its problems are the fitter's to report).
struct TakeSink {
  std::vector<TracePoint>& out;
  void problem(SampleProblem, std::int64_t, const std::string&) {}
  void sample(std::int64_t, std::int64_t t_us, double v) { out.push_back({static_cast<double>(t_us) / 1e6, v}); }
};

}  // namespace

std::string sse_event(std::string_view name, const Json& data) {
  return fmt::format("event: {}\ndata: {}\n\n", name, data.dump(-1, ' ', false, Json::error_handler_t::replace));
}

double WebRun::x0() const {
  if (std::isfinite(t_cut_s)) return t_cut_s;
  return trace.kept() > 0 ? trace.samples().front().t_s : 0.0;
}

bool WebLabOptions::is_valid(std::string* why) const {
  if (!(silent_after_s > 0)) return fail_why(why, "the silence limit must be positive");
  if (max_benches < 1) return fail_why(why, "at least one bench must be kept");
  if (runs_kept < 1) return fail_why(why, "at least one run per bench must be kept");
  if (max_run_samples < 2 || max_display_points < 2) return fail_why(why, "a run needs at least 2 samples and 2 points");
  for (const auto& id : expected_benches) {
    std::string bad;
    if (!is_valid_bench_id(id, &bad)) return fail_why(why, fmt::format("bench '{}': {}", id, bad));
  }
  return true;
}

WebLab::WebLab(WebLabOptions options) : opt_(std::move(options)), table_([&] {
  LabTableOptions t;
  t.lab_units = opt_.lab_units;
  t.signatures_checked = opt_.signatures_checked;
  t.stale_s = opt_.silent_after_s;
  t.max_benches = opt_.max_benches;
  return t;
}()) {
  for (const auto& id : opt_.expected_benches) {
    Bench& b = benches_[id];
    b.id = id;
    b.expected = true;
  }
}

WebLab::Bench* WebLab::find(std::string_view id) {
  auto it = benches_.find(id);
  return it == benches_.end() ? nullptr : &it->second;
}

const WebLab::Bench* WebLab::find(std::string_view id) const {
  auto it = benches_.find(id);
  return it == benches_.end() ? nullptr : &it->second;
}

bool WebLab::knows(std::string_view id) const { return find(id) != nullptr; }

WebLab::Bench& WebLab::bench(std::string_view id) {
  forget_dropped_rows();
  auto it = benches_.find(id);
  if (it == benches_.end()) {
    it = benches_.emplace(std::string(id), Bench{}).first;
    it->second.id = std::string(id);
  }
  return it->second;
}

// The table forgets the least recently heard bench past max_benches; so do the pages (a bench
// from a bench file stays, as it did before it was heard).
void WebLab::forget_dropped_rows() {
  if (table_.forgotten_rows() == forgotten_seen_) return;
  forgotten_seen_ = table_.forgotten_rows();
  for (auto it = benches_.begin(); it != benches_.end();) {
    if (!it->second.expected && !table_.bench(it->first))
      it = benches_.erase(it);
    else
      ++it;
  }
}

void WebLab::on_samples(std::string_view id, const samples_t& msg, std::int64_t now_us) {
  table_.on_samples(id, msg, now_us);
  Bench& b = bench(id);
  std::vector<TracePoint> kept;
  const auto n = static_cast<std::size_t>(std::max<std::int32_t>(0, msg.n));
  b.stream.take(msg, n, now_us, TakeSink{kept});  // also what waited past a gap this message filled
  if (kept.empty()) return;
  b.activity.last_sample_us = now_us;
  b.activity.last_value = kept.back().value;
  b.activity.quantity = msg.quantity;
  WebRun* current = b.runs.empty() ? nullptr : &b.runs.back();
  for (const TracePoint& p : kept) {
    if (current && current->open) {
      current->trace.add(p.t_s, p.value);
    } else {
      b.lead.push_back(p);
      while (b.lead.size() > opt_.lead_samples) b.lead.pop_front();
    }
  }
}

void WebLab::on_config(std::string_view id, const config_t& msg, std::int64_t now_us) {
  table_.on_config(id, msg, now_us);
  bench(id);
}

void WebLab::on_status(std::string_view channel_id, const status_t& msg, std::int64_t now_us) {
  table_.on_status(channel_id, msg, now_us);
  if (msg.service != "bridge") return;
  Bench& b = bench(channel_id);
  b.activity.reconnects = find_counter(msg, "reconnects").value_or(0);
  b.activity.last_status_us = now_us;
}

WebRun* WebLab::run_of(Bench& b, std::int32_t number, double t_cut_s) {
  for (auto it = b.runs.rbegin(); it != b.runs.rend(); ++it)
    if (it->number == number && (same_time(it->t_cut_s, t_cut_s) || std::isnan(t_cut_s) || std::isnan(it->t_cut_s)))
      return &*it;
  return nullptr;
}

WebRun& WebLab::start_run(Bench& b, std::int32_t number, double t_cut_s) {
  if (!b.runs.empty() && b.runs.back().open) close_run(b, b.runs.back());
  WebRun& r = b.runs.emplace_back(opt_.max_run_samples, opt_.max_display_points);
  r.number = number;
  r.key = b.next_key++;
  r.t_cut_s = t_cut_s;
  r.t_stop_s = nan;
  // The samples since the last run that belong to this one: from preroll_s before the cut (the
  // cut is seen a few samples late, so the coast so far is there too).
  const double from = std::isfinite(t_cut_s) ? t_cut_s - opt_.preroll_s : -std::numeric_limits<double>::infinity();
  std::size_t first = b.lead.size();
  while (first > 0 && b.lead[first - 1].t_s >= from) --first;
  for (std::size_t i = first; i < b.lead.size(); ++i) r.trace.add(b.lead[i].t_s, b.lead[i].value);
  b.lead.clear();
  while (b.runs.size() > opt_.runs_kept) b.runs.pop_front();
  b.detail_changed = true;
  return b.runs.back();
}

// A closed run takes no more samples: what follows is the lead of the next run.
void WebLab::close_run(Bench& b, WebRun& r) {
  r.open = false;
  b.detail_changed = true;
}

void WebLab::on_run(std::string_view id, const run_t& msg, std::int64_t now_us) {
  table_.on_run(id, msg, now_us);
  Bench& b = bench(id);
  WebRun* r = run_of(b, msg.run, msg.t_cut_s);
  if (!r) {
    r = &start_run(b, msg.run, msg.t_cut_s);
    // Joined after the run: it takes no samples (they are someone else's now).
    if (msg.state == run_t::STATE_ABANDONED) close_run(b, *r);
  }
  r->state = msg.state;
  r->partial = msg.lead_in == "none";
  if (std::isfinite(msg.t_cut_s)) r->t_cut_s = msg.t_cut_s;
  r->t_stop_s = msg.t_stop_s;
  r->note = msg.note;
  if (msg.state == run_t::STATE_ABANDONED && r->open) close_run(b, *r);
  b.detail_changed = true;
}

// A run that may take the headline: its cut seen, nothing doubted, and not ended by something that
// says the decline may be no coast at all: the reading rising again (a floating pin's hum closed at
// "power back") or the board resetting (a brown-out as the supply is switched: the stub before it
// is the board's, not the motor's). A coast whose samples stopped (its bench went silent, its bridge
// restarted, a gap, the memory bound) is still the coast it was, cut short and said so.
static bool whole_run(const fit_t& msg) {
  const bool interrupted = msg.end == "power back" || msg.end == "clock restart";
  return !interrupted && msg.lead_in != "none" && msg.ndoubts == 0;
}

void WebLab::on_fit(std::string_view id, const fit_t& msg, std::int64_t now_us) {
  table_.on_fit(id, msg, now_us);
  Bench& b = bench(id);
  WebRun* r = run_of(b, msg.run, msg.t_cut_s);
  if (!r) r = &start_run(b, msg.run, msg.t_cut_s);  // its RUN was not heard (this service started late)
  if (r->open) close_run(b, *r);
  r->partial = msg.lead_in == "none";
  if (std::isfinite(msg.t_stop_s)) r->t_stop_s = msg.t_stop_s;
  r->fit = fit_summary_json(msg, opt_.lab_units);
  // Whatever watch knows about the message's source is where its numbers are (issue 44 item 2): a
  // FIT from a session no fitter announced (any laptop) is marked, and never takes the headline
  // from a whole run the lab's fitter made.
  const LabBenchRow* row = table_.bench(id);
  const std::string doubt = row ? row->fit_doubt : std::string();
  if (!doubt.empty()) r->fit["not_verified"] = doubt;
  std::string why;
  auto curves = fit_curves_json(msg, &r->trace, opt_.curve_points, opt_.max_display_points, &why);
  if (curves) {
    r->curves = std::move(*curves);
  } else {
    r->curves = nullptr;
    table_.on_bad_message(fmt::format("SPINDOWN.{}.FIT run {}: {}", id, msg.run, why), now_us);
  }
  // The headline is the last whole run's: a run closed early (a reset, a new source, the power back,
  // silence, the memory cap), one whose cut was not seen or one the fitter doubts never replaces it
  // (a floating pin's hum cut as a run, a stub after a reset); it shows only while no whole run has.
  const bool whole = whole_run(msg) && doubt.empty();
  if (whole || !b.last_fit_whole) {
    b.last_fit = r->fit;
    b.last_fit_curve = best_curve_json(msg, tile_curve_points);
    b.last_fit_whole = whole;
  }
  if (std::isfinite(msg.zero_level)) b.activity.zero_level = msg.zero_level;
  b.detail_changed = true;
}

void WebLab::on_explain(std::string_view id, const explain_t& msg, std::int64_t) {
  Bench& b = bench(id);
  for (auto it = b.runs.rbegin(); it != b.runs.rend(); ++it)
    if (it->number == msg.run) {
      it->explain = explain_json(msg, opt_.lab_units);
      b.detail_changed = true;
      return;
    }
}

void WebLab::on_bad_message(std::string text, std::int64_t now_us) { table_.on_bad_message(std::move(text), now_us); }

void WebLab::on_refused(const GateResult& refused, std::int64_t now_us, std::string_view id, std::string_view about) {
  ++refused_;
  last_refused_ = refused.text;
  if (refused.verdict == GateVerdict::other_lab) return;
  if (id.empty()) {
    if (auto it = benches_.find(std::string(about)); it != benches_.end()) {
      it->second.refused_other = fmt::format("{}: {}", gate_verdict_name(refused.verdict), refused.text);
      it->second.refused_other_us = now_us;
    }
    return;
  }
  bench(id);  // a tile for a bench whose every sample is refused (the summary says so)
  table_.on_refused(refused, now_us, id);
}

// ---- JSON ------------------------------------------------------------------------------------------

Json WebLab::run_summary_json(const Bench& b, const WebRun& r, bool counts) const {
  Json j;
  j["number"] = r.number;
  j["key"] = r.key;
  j["state"] = std::string(run_state_name(r.state));
  j["partial"] = r.partial;
  j["open"] = r.open;
  j["note"] = r.note;
  j["t_cut_s"] = json_number(r.t_cut_s);
  j["t_stop_s"] = json_number(r.t_stop_s);
  if (counts) {  // not in a tile's pushed summary: it would change with every sample
    j["samples"] = r.trace.received();
    j["kept"] = r.trace.kept();
    j["truncated"] = r.trace.truncated();
  }
  j["csv"] = fmt::format("/bench/{}/runs/{}.csv", b.id, r.number);
  j["fit"] = r.fit;
  return j;
}

Json WebLab::summary_json(const Bench& b, std::int64_t now_us, bool counters) const {
  const LabBenchRow* row = table_.bench(b.id);
  Json j;
  j["id"] = b.id;
  const bool refused = row && table_.refused_now(*row, now_us);
  j["state"] = refused ? std::string("refused")
                       : std::string(bench_state_name(bench_state(row, b.activity, now_us, opt_.silent_after_s)));
  j["refused"] = refused ? row->refused : std::string();
  // While silent, when its last sample came (host time, ms since 1970): the page counts its age
  // (fixed while silent, so the pushed summary does not change with the clock).
  const std::string_view health = bridge_health(row, b.activity, now_us, opt_.silent_after_s);
  if ((j["state"] == "silent" || health == "unplugged") && b.activity.last_sample_us > 0)
    j["last_sample_unix_ms"] = b.activity.last_sample_us / 1000;
  // Messages for this bench the gate refused in the last ten minutes (unsigned, another key, a
  // replay, …): said on its tile and page, where its numbers are, not only in the footer.
  if (b.refused_other_us > 0 && (!row || b.refused_other_us >= row->refused_us) && now_us - b.refused_other_us <= 600'000'000)
    j["refused_recent"] = b.refused_other;
  else if (row && row->refused_us > 0 && now_us - row->refused_us <= 600'000'000)
    j["refused_recent"] = fmt::format("{}: {}", row->refused_kind, row->refused);
  j["expected"] = b.expected;
  j["unit"] = std::string(unit_of(b.activity.quantity));
  Json bridge;
  bridge["health"] = std::string(health);
  bridge["state"] = row && row->has_bridge ? row->bridge_state : std::string();
  bridge["reconnects"] = b.activity.reconnects;
  bridge["rate_hz"] = row && row->has_bridge ? std::round(row->rate_hz) : 0.0;
  bridge["error"] = row ? row->bridge_error : std::string();
  if (counters) {
    bridge["lines_good"] = row ? row->lines_good : 0;
    bridge["lines_bad"] = row ? row->lines_bad : 0;
    bridge["seq_gaps"] = row ? row->seq_gaps : 0;
    bridge["samples_missing"] = row ? row->samples_missing : 0;
  }
  j["bridge"] = std::move(bridge);
  j["run"] = b.runs.empty() ? Json(nullptr) : run_summary_json(b, b.runs.back(), counters);
  j["last_fit"] = b.last_fit;
  j["last_fit_curve"] = b.last_fit_curve;
  if (counters) {
    j["value"] = json_number(b.activity.last_value);
    j["last_sample_age_s"] = b.activity.last_sample_us > 0 ? Json(1e-6 * double(now_us - b.activity.last_sample_us))
                                                          : Json(nullptr);
    j["samples"] = row ? row->samples : 0;
    j["fits"] = row ? row->fits : 0;
  }
  return j;
}

Json WebLab::points_json(const Bench& b, std::size_t first, std::size_t step, bool reset) const {
  Json j;
  if (b.runs.empty()) {
    j["key"] = 0;
    j["reset"] = reset;
    j["n"] = 0;
    j["x0"] = 0;
    j["p"] = Json::array();
  } else {
    const WebRun& r = b.runs.back();
    const double x0 = r.x0();
    Json p = Json::array();
    for (std::size_t i = first; i < r.trace.display_size(); i += step) {
      const TracePoint& t = r.trace.display_point(i);
      p.push_back(plot_point(t.t_s - x0, t.value));
    }
    j["key"] = r.key;
    j["reset"] = reset;
    j["n"] = r.trace.received();
    j["x0"] = x0;
    j["p"] = std::move(p);
  }
  j["live"] = json_number(b.activity.last_value);
  return j;
}

Json WebLab::detail_json(const Bench& b) const {
  Json j;
  j["bench"] = b.id;
  j["unit"] = std::string(unit_of(b.activity.quantity));
  if (b.runs.empty()) {
    j["run"] = nullptr;
  } else {
    const WebRun& r = b.runs.back();
    Json rj = run_summary_json(b, r);
    const double x0 = r.x0();
    rj["x0"] = x0;
    Json markers;
    markers["cut"] = std::isfinite(r.t_cut_s) && !r.partial ? Json(r.t_cut_s - x0) : Json(nullptr);
    markers["stop"] = std::isfinite(r.t_stop_s) ? Json(r.t_stop_s - x0) : Json(nullptr);
    rj["markers"] = std::move(markers);
    rj["curves"] = r.curves;
    rj["explain"] = r.explain;
    j["run"] = std::move(rj);
  }
  Json earlier = Json::array();
  for (std::size_t i = 0; i + 1 < b.runs.size(); ++i) earlier.push_back(run_summary_json(b, b.runs[i]));
  j["earlier"] = std::move(earlier);
  return j;
}

Json WebLab::lab_json(std::int64_t now_us) const {
  Json j;
  Json services = Json::array();
  for (const LabServiceRow* s : table_.services()) {
    const double age = 1e-6 * double(now_us - s->last_message_us);
    services.push_back({{"service", s->service},
                        {"instance", s->instance},
                        {"host", s->host},
                        {"state", age > opt_.silent_after_s ? std::string("silent") : s->state},
                        {"last_error", s->last_error}});
  }
  j["services"] = std::move(services);
  j["bad_messages"] = table_.bad_messages();
  j["refused_messages"] = refused_;
  j["last_refused"] = last_refused_;
  j["lab_units"] = opt_.lab_units;
  j["name"] = opt_.lab_name;
  return j;
}

std::vector<const WebLab::Bench*> WebLab::ordered() const {
  std::vector<const Bench*> out;
  for (const auto& [id, b] : benches_) out.push_back(&b);
  return out;  // std::map: sorted by id
}

Json WebLab::state_json(std::int64_t now_us) const {
  Json benches = Json::array();
  for (const Bench* b : ordered()) benches.push_back(summary_json(*b, now_us, true));
  Json j;
  j["benches"] = std::move(benches);
  j["lab"] = lab_json(now_us);
  j["generated_us"] = now_us;
  return j;
}

std::optional<Json> WebLab::bench_json(std::string_view id, std::int64_t now_us) const {
  const Bench* b = find(id);
  if (!b) return std::nullopt;
  Json j;
  j["bench"] = summary_json(*b, now_us, true);
  j["detail"] = detail_json(*b);
  j["samples"] = points_json(*b, 0, 1, true);
  return j;
}

std::optional<Json> WebLab::run_json(std::string_view id, std::int32_t number) const {
  const Bench* b = find(id);
  if (!b) return std::nullopt;
  for (auto it = b->runs.rbegin(); it != b->runs.rend(); ++it) {
    if (it->number != number) continue;
    Json j = run_summary_json(*b, *it);
    const double x0 = it->x0();
    j["x0"] = x0;
    Json p = Json::array();
    for (std::size_t i = 0; i < it->trace.display_size(); ++i)
      p.push_back(plot_point(it->trace.display_point(i).t_s - x0, it->trace.display_point(i).value));
    j["points"] = std::move(p);
    j["curves"] = it->curves;
    return j;
  }
  return std::nullopt;
}

std::optional<std::string> WebLab::run_csv(std::string_view id, std::int32_t number) const {
  const Bench* b = find(id);
  if (!b) return std::nullopt;
  for (auto it = b->runs.rbegin(); it != b->runs.rend(); ++it)
    if (it->number == number) return it->trace.csv();
  return std::nullopt;
}

std::string WebLab::snapshot_event(std::string_view id, std::int64_t now_us) const {
  Json j;
  Json benches = Json::array();
  Json samples = Json::object();
  if (id.empty()) {
    for (const Bench* b : ordered()) {
      benches.push_back(summary_json(*b, now_us, false));
      const std::size_t shown = b->runs.empty() ? 0 : b->runs.back().trace.display_size();
      const std::size_t step = std::max<std::size_t>(1, (shown + opt_.tile_points - 1) / std::max<std::size_t>(1, opt_.tile_points));
      samples[b->id] = points_json(*b, 0, step, true);
    }
  } else if (const Bench* b = find(id)) {
    benches.push_back(summary_json(*b, now_us, false));
    samples[b->id] = points_json(*b, 0, 1, true);
    j["detail"] = detail_json(*b);
  }
  j["benches"] = std::move(benches);
  j["samples"] = std::move(samples);
  j["lab"] = lab_json(now_us);
  j["page"] = std::string(id.empty() ? "room" : "bench");
  return sse_event("snapshot", j);
}

std::vector<WebUpdate> WebLab::take_updates(std::int64_t now_us) {
  forget_dropped_rows();
  std::vector<WebUpdate> out;
  const auto make = [](std::string_view name, const Json& data) {
    return std::make_shared<const std::string>(sse_event(name, data));
  };

  // The list of benches (a bench heard for the first time, or forgotten).
  Json roster = Json::array();
  for (const Bench* b : ordered()) roster.push_back(b->id);
  if (std::string r = roster.dump(); r != sent_roster_) {
    sent_roster_ = std::move(r);
    out.push_back({WebUpdate::To::room, {}, make("roster", Json{{"benches", roster}})});
  }
  if (std::string lab = lab_json(now_us).dump(); lab != sent_lab_) {
    out.push_back({WebUpdate::To::everyone, {}, make("lab", Json::parse(lab))});
    sent_lab_ = std::move(lab);
  }

  Json room_samples = Json::object();
  for (auto& [id, b] : benches_) {
    if (std::string s = summary_json(b, now_us, false).dump(); s != b.sent_summary) {
      b.sent_summary = std::move(s);
      out.push_back({WebUpdate::To::room_and_bench, id,
                     std::make_shared<const std::string>(fmt::format("event: bench\ndata: {}\n\n", b.sent_summary))});
    }
    if (b.detail_changed) {
      b.detail_changed = false;
      out.push_back({WebUpdate::To::bench, id, make("detail", detail_json(b))});
    }
    // New points of the current run (all of them again for a new run or a coarser display).
    const WebRun* r = b.runs.empty() ? nullptr : &b.runs.back();
    const std::int64_t key = r ? r->key : 0;
    const std::size_t stride = r ? r->trace.stride() : 0, shown = r ? r->trace.display_size() : 0;
    const std::int64_t received = r ? r->trace.received() : 0;
    const bool reset = key != b.sent_key || stride != b.sent_stride;
    const double live = b.activity.last_value;
    const bool live_changed = !same_time(live, b.sent_live);
    if (reset || shown > b.sent_points || received != b.sent_received || live_changed) {
      Json p = points_json(b, reset ? 0 : b.sent_points, 1, reset);
      b.sent_key = key;
      b.sent_stride = stride;
      b.sent_points = shown;
      b.sent_received = received;
      b.sent_live = live;
      Json one = Json::object();
      one[id] = p;
      out.push_back({WebUpdate::To::bench, id, make("samples", Json{{"benches", std::move(one)}})});
      if (reset || !p["p"].empty()) room_samples[id] = std::move(p);
    }
  }
  if (!room_samples.empty())
    out.push_back({WebUpdate::To::room, {}, make("samples", Json{{"benches", std::move(room_samples)}})});
  return out;
}

}  // namespace spindown
