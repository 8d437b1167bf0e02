// FitterCore: the run detector's events become RUN messages, a closed run is fitted and its FIT
// published; finish() and poll() close what is still open.
#include "spindown/fitter_core.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <fmt/format.h>
#include <limits>
#include <optional>
#include <regex>

#include "spindown/fit_message.hpp"
#include "spindown/lcm_channels.hpp"

#include "fitter_bench.hpp"

namespace spindown {

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Whether the command line or the bench's file names J, K_b or their uncertainties.
bool names_bench(const BenchChoice& named, const BenchFile* file) {
  return named.inertia_given || named.kb_given || named.inertia_error_given || named.kb_error_given ||
         (file && (file->sets_inertia || file->sets_kb || file->sets_inertia_error || file->sets_kb_error));
}

// Where each of J and K_b came from, by choose_bench_params' rule, and what the CONFIG said when
// it was overruled: "J: --inertia (over the log's CONFIG: 1.12688e-05 kg·m²); K_b: CONFIG".
std::string named_bench_source(const BenchChoice& named, const BenchFile* file, const std::optional<BenchParams>& config) {
  const auto one = [&](const char* what, bool given, bool file_sets, double config_value, const char* unit) {
    std::string from = given ? std::string("the command line")
                       : file_sets ? fmt::format("bench file {}", file->path)
                       : config   ? std::string("CONFIG")
                                  : std::string("the default");
    if ((given || file_sets) && config)
      from += fmt::format(" (over the log's CONFIG: {:.6g} {})", config_value, unit);
    return fmt::format("{}: {}", what, from);
  };
  return one("J", named.inertia_given, file && file->sets_inertia, config ? config->inertia_kg_m2 : 0, "kg·m²") + "; " +
         one("K_b", named.kb_given, file && file->sets_kb, config ? config->kb_v_s_per_rad : 0, "V·s/rad");
}

}  // namespace

void FitterCore::publish_run(Bench& b, const Run& run, std::int8_t state, std::string note, std::int64_t utime) {
  const Bench::Sample* first = b.at(run.cut_index);
  const std::size_t last_index = b.detector.samples_seen() > 0 ? b.detector.samples_seen() - 1 : 0;
  std::size_t end = last_index + 1;
  if (state == run_t::STATE_ABANDONED || (state == run_t::STATE_STOPPED && run.end_index > run.cut_index))
    end = std::max(run.end_index, run.cut_index + 1);
  const Bench::Sample* last = b.at(end - 1);
  const std::int64_t samples = end > run.cut_index ? std::int64_t(end - run.cut_index) : 0;
  run_t m = to_run_message(b.id, run, state, first ? first->seq : -1, last ? last->seq : -1,
                           static_cast<std::int32_t>(samples), std::move(note), utime);
  m.bridge_host = b.run_host;
  m.bridge_session = static_cast<std::int64_t>(b.run_session);
  sink_.run_changed(m);
}

void FitterCore::handle_events(Bench& b, std::int64_t recv_utime) {
  for (RunEvent& e : b.detector.take_events()) {
    if (e.has_diagnostic) sink_.diagnostic(b.id, e.diagnostic);
    switch (e.kind) {
      case RunEvent::Kind::cut:
        ++counters_.runs_started;
        b.run_host = b.stream.host;  // the run is this source's, whoever comes later
        b.run_session = b.stream.session;
        b.open_state = 1;
        b.open_run = e.run;
        publish_run(b, e.run, run_t::STATE_COASTING,
                    e.run.partial() ? std::string("cut not seen: joined mid-coast, a partial run from its first sample")
                                    : fmt::format("cut (lead-in: {})", e.run.lead_in),
                    recv_utime);
        break;
      case RunEvent::Kind::stop:
        b.open_state = 2;
        b.open_run = e.run;
        publish_run(b, e.run, run_t::STATE_STOPPED, "standstill: collecting the tail before fitting", recv_utime);
        break;
      case RunEvent::Kind::complete:
        b.open_state = 0;
        counters_.partial_runs += e.run.partial();
        counters_.silent_benches += e.run.end == Run::End::silent;
        fit_and_publish(b, e.run, e.has_diagnostic && !e.run.stopped ? e.diagnostic.message : std::string(),
                        recv_utime);
        break;
      case RunEvent::Kind::ignored:
        ++counters_.runs_ignored;
        b.open_state = 0;
        publish_run(b, e.run, run_t::STATE_ABANDONED, e.has_diagnostic ? e.diagnostic.message : "ignored",
                    recv_utime);
        break;
      case RunEvent::Kind::diagnostic: break;
    }
  }
}

void FitterCore::fit_and_publish(Bench& b, const Run& run, const std::string& why_unstopped, std::int64_t recv_utime) {
  ++counters_.runs;
  const Bench::Sample* first = b.at(run.cut_index);
  const Bench::Sample* last = run.end_index > run.cut_index ? b.at(run.end_index - 1) : first;
  if (!first || !last) {
    ++counters_.internal_errors;
    error(fmt::format("{}: run {} (samples {}..{}) is no longer buffered; not fitted", b.channel, run.number,
                      run.cut_index, run.end_index),
          recv_utime);
    return;
  }
  const std::string note = run.stopped ? std::string("complete: fitted")
                                       : why_unstopped.empty()
                                           ? fmt::format("closed without a stop ({}); fitted", end_name(run.end))
                                           : fmt::format("closed without a stop: {}; fitted", why_unstopped);
  publish_run(b, run, run.stopped ? run_t::STATE_STOPPED : run_t::STATE_ABANDONED, note, recv_utime);

  // The run's samples as contiguous arrays, indices relative to the cut.
  const std::size_t base = b.base();
  const std::size_t count = run.end_index > run.cut_index ? run.end_index - run.cut_index : 0;
  scratch_t_.resize(count);
  scratch_v_.resize(count);
  for (std::size_t k = 0; k < count; ++k) {
    const Bench::Sample& s = b.mirror[run.cut_index + k - base];
    scratch_t_[k] = s.t_s;
    scratch_v_[k] = s.value;
  }
  Run local = run;
  local.cut_index = 0;
  local.stop_index = run.stop_index - run.cut_index;
  local.end_index = run.end_index - run.cut_index;
  for (std::size_t& k : local.outliers) k -= run.cut_index;

  FitResult r;
  r.bench = b.id;
  r.bridge_host = b.run_host;
  r.bridge_session = b.run_session;
  r.first_seq = first->seq;
  r.last_seq = last->seq;
  r.detected_utime = recv_utime;
  FitOptions fo;
  fo.models = opt_.models;
  const auto file_it = opt_.bench_files.find(b.id);
  const BenchFile* file = file_it == opt_.bench_files.end() ? nullptr : &file_it->second;
  if (names_bench(opt_.named, file)) {
    const std::optional<BenchParams> config = opt_.ignore_config ? std::nullopt : b.config;
    fo.bench = choose_bench_params(opt_.named, file, config);
    r.bench_source = named_bench_source(opt_.named, file, config);
  } else if (opt_.ignore_config) {
    fo.bench = opt_.default_bench;
    r.bench_source = "default (CONFIG ignored by option)";
  } else if (b.config) {
    fo.bench = *b.config;
    r.bench_source = "config";
  } else {
    fo.bench = opt_.default_bench;
    r.bench_source = b.config_problem.empty()
                         ? fmt::format("default ({}): no CONFIG received from bench {}", opt_.default_bench.inertia_source,
                                       b.id)
                         : fmt::format("default ({}): {}", opt_.default_bench.inertia_source, b.config_problem);
  }
  // One window for the fit and its explanation (run_window.hpp): the same samples, outliers and
  // weights as spindown fit and explain take from a file.
  const auto t0 = std::chrono::steady_clock::now();
  const RunWindow window(scratch_t_, scratch_v_, local, fo.weighted);
  try {
    r.fit = fit_run(window, b.stream.quantity, local, fo);
  } catch (const std::exception& e) {
    ++counters_.internal_errors;
    error(fmt::format("{}: run {}: the fit failed: {}", b.channel, run.number, e.what()), recv_utime);
    return;
  }
  r.fit_seconds = seconds_since(t0);
  r.window = local;
  r.fit.run = run;  // indices as in the bench's stream
  if (r.fit.best.empty()) {
    ++counters_.fit_failures;
    error(fmt::format("{}: run {}: no model converged", b.channel, run.number), recv_utime);
  }
  if (auto h = opt_.health.find(b.id); h != opt_.health.end()) {
    try {
      r.health = assess_health(r.fit, h->second);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: run {}: the health verdict failed: {}", b.channel, run.number, e.what()), recv_utime);
    }
  }
  r.t_s = scratch_t_;
  r.value = scratch_v_;
  ++counters_.fits;
  sink_.fit_ready(r);
  // The discrepancy workflow on the same window, once the FIT is out.
  if (!opt_.explain_base.empty()) {
    try {
      ExplainOptions eo;
      eo.bench = r.fit.bench;
      eo.base = opt_.explain_base;
      eo.weighted = window.weighted();
      r.explain = explain_run(window, r.fit.quantity, local, eo, b.lowest_reading);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: run {}: the explain workflow failed: {}", b.channel, run.number, e.what()), recv_utime);
    }
    sink_.explain_ready(r);  // r.explain empty when it failed (said above)
  }
}

void FitterCore::finish(std::int64_t now_utime) {
  std::vector<Bench*> order;
  for (auto& [id, b] : benches_) order.push_back(b.get());
  std::sort(order.begin(), order.end(), [](const Bench* a, const Bench* b) { return a->arrival < b->arrival; });
  for (Bench* b : order) {
    try {
      flush_stream(*b, now_utime);  // a held jump nothing contradicted, sources that never took over
      b->detector.finish();
      handle_events(*b, now_utime);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: internal error at the end: {}", b->channel, e.what()), now_utime);
    }
    trim_mirror(*b);
  }
}

void FitterCore::abandon_open_runs(std::int64_t now_utime, const std::string& why) {
  std::vector<Bench*> order;
  for (auto& [id, b] : benches_) order.push_back(b.get());
  std::sort(order.begin(), order.end(), [](const Bench* a, const Bench* b) { return a->arrival < b->arrival; });
  for (Bench* b : order) {
    if (b->open_state == 0) continue;
    Run run = b->open_run;
    run.end_index = b->detector.samples_seen();  // every sample it had when the fitter stopped
    ++counters_.runs_abandoned;
    publish_run(*b, run, run_t::STATE_ABANDONED, why, now_utime);
    b->open_state = 0;
  }
}

bool FitterCore::silence_due(std::int64_t now_utime) const {
  const auto silent_us = static_cast<std::int64_t>(opt_.silent_s * 1e6);
  for (const auto& [id, b] : benches_)
    if (b->open_state != 0 && now_utime - b->last_sample_utime >= silent_us) return true;
  return false;
}

void FitterCore::poll(std::int64_t now_utime) {
  const auto silent_us = static_cast<std::int64_t>(opt_.silent_s * 1e6);
  for (auto& [id, b] : benches_) {
    if (b->stream.waiting()) {  // gaps that waited long enough for late messages are lost
      try {
        expire_stream(*b, now_utime);
      } catch (const std::exception& e) {
        ++counters_.internal_errors;
        error(fmt::format("{}: internal error taking what waited past a gap: {}", b->channel, e.what()), now_utime);
      }
    }
    if (b->open_state == 0 || now_utime - b->last_sample_utime < silent_us) continue;
    if (now_utime - b->last_refused_utime < silent_us) {  // its samples arrive and are refused: not silent
      if (!b->refused_said) {
        b->refused_said = true;
        std::string text = fmt::format("{}: run {} is kept open: the bench still sends, but its samples are refused ({})",
                                       b->channel, b->open_run.number, b->last_refused);
        sink_.notice("kept open", b->channel, text);
        error(std::move(text), now_utime);
      }
      continue;
    }
    b->refused_said = false;
    try {
      b->detector.went_silent(opt_.silent_s);  // not the silence measured: live and refit say the same
      handle_events(*b, now_utime);
    } catch (const std::exception& e) {
      ++counters_.internal_errors;
      error(fmt::format("{}: internal error closing a silent bench's run: {}", b->channel, e.what()), now_utime);
    }
    trim_mirror(*b);
  }
}

}  // namespace spindown
