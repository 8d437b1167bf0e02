#include "refit_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <regex>
#include <string_view>
#include <unistd.h>
#include <vector>

#include "exit_codes.hpp"
#include "file_problems.hpp"
#include "spindown/bench.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/progress.hpp"

namespace spindown::cli {

namespace {

constexpr std::size_t max_problems_listed = 20;  // per file, then counted

constexpr std::size_t max_detector_notes = 1000;  // per file, then counted (memory flat)

class RefitSink final : public FitterSink {
 public:
  RefitSink(LogRefit& out, const std::string& path, const RefitRunFn& each_run)
      : out_(out), path_(path), each_run_(each_run) {}
  void run_changed(const run_t&) override {}
  void fit_ready(const FitResult& r) override {
    ++out_.runs_fitted;
    if (!each_run_) {
      out_.runs.push_back({r.bench, r.fit, r.bench_source, r.first_seq, r.last_seq});
      return;
    }
    if (r.fit.best.empty())
      out_.file.failures.push_back(fmt::format("SPINDOWN.{}.SAMPLE: run {}: no model converged", r.bench,
                                               r.fit.run.number));
    each_run_(RefitRun{r.bench, r.fit, r.bench_source, r.first_seq, r.last_seq});
  }
  void problem(const std::string& text) override {
    if (++problems_ <= max_problems_listed)
      out_.file.diagnostics.push_back({Diagnostic::Severity::warning, path_, 0, text});
  }
  void diagnostic(const std::string&, const Diagnostic& d) override {
    if (++notes_ > max_detector_notes) return;
    Diagnostic copy = d;
    copy.source = path_ + " " + d.source;
    out_.file.diagnostics.push_back(std::move(copy));
  }
  std::size_t problems() const { return problems_; }
  std::size_t notes() const { return notes_; }

 private:
  LogRefit& out_;
  const std::string& path_;
  const RefitRunFn& each_run_;
  std::size_t problems_ = 0, notes_ = 0;
};

// One bench's formatted runs, held in an unlinked temporary file until the log is done (in
// memory only if no temporary file can be made), so memory stays flat however long the log.
class RunSpool {
 public:
  RunSpool() : file_(std::tmpfile()) {}
  ~RunSpool() {
    if (file_) std::fclose(file_);
  }
  RunSpool(const RunSpool&) = delete;
  RunSpool& operator=(const RunSpool&) = delete;
  void add(std::string_view text) {
    ++runs_;
    if (file_ && std::fwrite(text.data(), 1, text.size(), file_) == text.size()) return;
    if (file_) {  // disk full: keep what is already spooled, carry on in memory
      spilled_ = true;
    }
    memory_.append(text);
  }
  std::size_t runs() const { return runs_; }
  // Copies everything to out, leaving out the first skip bytes.
  void copy_to(std::ostream& out, std::size_t skip) {
    if (file_) {
      std::fflush(file_);
      std::rewind(file_);
      std::vector<char> block(1 << 16);
      std::size_t got = 0;
      while ((got = std::fread(block.data(), 1, block.size(), file_)) > 0) {
        const std::size_t from = std::min(skip, got);
        out.write(block.data() + from, static_cast<std::streamsize>(got - from));
        skip -= from;
      }
    }
    out << std::string_view(memory_).substr(std::min(skip, memory_.size()));
  }

 private:
  std::FILE* file_ = nullptr;
  std::string memory_;
  bool spilled_ = false;
  std::size_t runs_ = 0;
};

std::string indented(const std::string& text, std::size_t spaces) {
  const std::string pad(spaces, ' ');
  std::string out;
  out.reserve(text.size() + text.size() / 4);
  out += pad;
  std::size_t from = 0;
  for (std::size_t nl; (nl = text.find('\n', from)) != std::string::npos; from = nl + 1) {
    out.append(text, from, nl + 1 - from);
    out += pad;
  }
  out.append(text, from);
  return out;
}

std::string dump_json(const Json& j) { return j.dump(2, ' ', false, Json::error_handler_t::replace); }

// The first place two JSON values differ ("" when equal).
std::string first_difference(const Json& a, const Json& b, const std::string& path) {
  if (a.type() != b.type()) return fmt::format("{}: {} vs {}", path, a.dump(), b.dump());
  if (a.is_object()) {
    for (const auto& [key, value] : a.items()) {
      if (!b.contains(key)) return fmt::format("{}.{}: only in the refit", path, key);
      if (auto d = first_difference(value, b.at(key), path + "." + key); !d.empty()) return d;
    }
    for (const auto& [key, value] : b.items())
      if (!a.contains(key)) return fmt::format("{}.{}: only in the live result", path, key);
    return {};
  }
  if (a.is_array()) {
    if (a.size() != b.size()) return fmt::format("{}: {} vs {} elements", path, a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i)
      if (auto d = first_difference(a[i], b[i], fmt::format("{}[{}]", path, i)); !d.empty()) return d;
    return {};
  }
  return a == b ? std::string() : fmt::format("{}: {} vs {}", path, a.dump(), b.dump());
}

FitterOptions fitter_options(const RefitCommandOptions& o) {
  FitterOptions f;
  f.bench_regex = o.bench_regex;
  f.ignore_config = o.ignore_config;
  f.max_benches = o.max_benches;
  f.admit_rate_hz = o.admit_rate_hz;
  f.silent_s = o.silent_s;
  f.max_rate_hz = 0;  // a log is read as fast as the disk allows; live caps were applied live
  if (o.inertia_given) {
    f.default_bench.inertia_kg_m2 = o.inertia_kg_m2;
    f.default_bench.inertia_source = "--inertia";
  }
  if (o.kb_given) {
    f.default_bench.kb_v_s_per_rad = o.kb_v_s_per_rad;
    f.default_bench.kb_source = "--kb";
  } else if (o.speed_constant_given) {
    f.default_bench.kb_v_s_per_rad = kb_from_speed_constant(o.speed_constant_rpm_per_v);
    f.default_bench.kb_source = fmt::format("--speed-constant {} rpm/V", o.speed_constant_rpm_per_v);
  }
  if (!o.models.empty()) {
    f.models.clear();
    for (const auto& name : o.models) {
      auto kind = parse_model(name);
      if (!kind) throw CLI::ValidationError(fmt::format("--models: unknown model '{}' (viscous, coulomb, combined)", name));
      f.models.push_back(*kind);
    }
  }
  std::string why;
  if (!f.is_valid(&why)) throw CLI::ValidationError(why);
  return f;
}

// Seconds of device time two fitted windows share (a recorded FIT as JSON); 0 when apart. A
// window of one sample counts as a period long.
double number_in(const Json& j, const char* key) {
  const auto it = j.find(key);
  return it != j.end() && it->is_number() ? it->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

double window_overlap_s(const Run& ours, const Json& theirs) {
  const double t0 = number_in(theirs, "t_cut_s"), t1 = number_in(theirs, "t_end_s");
  const double pad = std::max(ours.period_s, 1e-3);
  const double lo = std::max(ours.t_cut_s, t0), hi = std::min(ours.t_end_s, std::isfinite(t1) ? t1 : t0) + pad;
  return std::isfinite(lo) && std::isfinite(hi) && hi > lo ? hi - lo : 0.0;
}

}  // namespace

LogRefit refit_log(const std::string& path, const FitterOptions& options, bool keep_live_fits,
                   const std::function<void(const LcmLogEvent&)>& each_event, const RefitProgressFn& progress,
                   const RefitRunFn& each_run) {
  LogRefit out;
  out.file.file = path;
  // The core reads samples in place; a caller that sees each event may want the samples_t.
  LcmLogReader reader(path, each_event ? LcmSamples::view_and_message : LcmSamples::view_only);
  if (!reader.good()) {
    out.file.failures.push_back(reader.open_error());
    return out;
  }
  RefitSink sink(out, path, each_run);
  FitterCore core(options, sink);
  std::map<std::string, std::size_t, std::less<>> order;
  std::vector<char> channel_done;  // by LcmLogEvent::channel_id: its bench's place is known
  std::int64_t last_utime = 0, next_poll = std::numeric_limits<std::int64_t>::min();
  std::size_t file_problems = 0;
  LcmLogEvent ev;
  // Progress every 256 events, counted down (one test per event, none for a caller without one).
  constexpr std::size_t progress_every = 256;
  std::size_t until_progress = progress ? progress_every : std::numeric_limits<std::size_t>::max();
  while (reader.next(ev)) {
    if (each_event) each_event(ev);
    if (--until_progress == 0) {
      until_progress = progress_every;
      progress(ev.file_offset, reader.file_size(), out.runs_fitted);
    }
    if (ev.number > 0) last_utime = ev.log_utime;
    // Host time passes as the log's events do: benches gone silent mid-coast are closed as live.
    if (ev.log_utime >= next_poll) {
      core.poll(ev.log_utime);
      next_poll = ev.log_utime + FitterCore::poll_period_us;
    }
    // A bench's first SAMPLE/CONFIG fixes its place; checked once per channel, not per event.
    const auto id = static_cast<std::size_t>(ev.channel_id);
    if (ev.channel_id < 0 || id >= channel_done.size() || !channel_done[id]) {
      if (!ev.bench.empty() && (ev.channel.ends_with(".SAMPLE") || ev.channel.ends_with(".CONFIG")) &&
          !order.contains(ev.bench)) {
        order.emplace(ev.bench, order.size());
        out.bench_order.emplace_back(ev.bench);
      }
      if (ev.channel_id >= 0) {
        if (id >= channel_done.size()) channel_done.resize(id + 1, 0);
        channel_done[id] = 1;
      }
    }
    switch (ev.kind) {
      // Decoded (and checked) once, by the reader: the core takes the message as it is.
      case LcmLogEvent::Kind::samples:
        core.on_samples(ev.channel_id, ev.bench, ev.samples_view, ev.log_utime);
        break;
      case LcmLogEvent::Kind::config:
        core.on_config(ev.bench, ev.config, ev.log_utime);
        break;
      case LcmLogEvent::Kind::problem:
        if (ev.number > 0 && ev.data) {  // a message that does not decode: the core counts it
          core.on_message(ev.channel, ev.data, ev.data_size, ev.log_utime);
        } else if (++file_problems <= max_problems_listed) {
          out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, ev.number, ev.problem});
        }
        break;
      case LcmLogEvent::Kind::other:
        if (keep_live_fits && ev.channel.starts_with("SPINDOWN.") && ev.channel.ends_with(".FIT")) {
          fit_t m;
          try {
            if (m.decode(ev.data, 0, ev.data_size) >= 0) {
              out.live.push_back(std::move(m));
              break;
            }
          } catch (const std::exception&) {
          }
          out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, ev.number,
                                          fmt::format("event {} on {}: not a decodable fit_t; skipped", ev.number,
                                                      ev.channel)});
        }
        break;
    }
  }
  core.finish(last_utime);
  out.counters = core.counters();
  const FitterCounters& c = out.counters;
  if (file_problems > max_problems_listed)
    out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                                    fmt::format("{} damaged parts of the file in all", file_problems)});
  if (sink.problems() > max_problems_listed)
    out.file.diagnostics.push_back({Diagnostic::Severity::warning, path, 0,
                                    fmt::format("{} unusable messages or samples in all (first {} listed)",
                                                sink.problems(), max_problems_listed)});
  if (sink.notes() > max_detector_notes)
    out.file.diagnostics.push_back({Diagnostic::Severity::note, path, 0,
                                    fmt::format("{} run detector notes in all (first {} listed)", sink.notes(),
                                                max_detector_notes)});
  out.file.diagnostics.push_back(
      {Diagnostic::Severity::note, path, 0,
       fmt::format("{} events: {} sample messages, {} config messages, {} samples used; {} decode errors, {} sequence "
                   "gaps ({} samples lost), {} repeated messages, {} NaN values, {} samples with time going back, "
                   "{} clock restarts",
                   reader.events_read(), c.sample_messages, c.config_messages, c.samples, c.decode_errors, c.seq_gaps,
                   c.samples_lost, c.duplicates, c.nan_values, c.time_backwards, c.clock_restarts)});

  // Runs in the order `spindown fit` lists them: by bench (first appearance), then number.
  auto rank = [&](const std::string& bench) {
    auto it = order.find(bench);
    return it == order.end() ? order.size() : it->second;
  };
  std::stable_sort(out.runs.begin(), out.runs.end(), [&](const RefitRun& a, const RefitRun& b) {
    const auto ra = rank(a.bench), rb = rank(b.bench);
    return ra != rb ? ra < rb : a.fit.run.number < b.fit.run.number;
  });
  out.file.samples = static_cast<std::size_t>(c.samples);
  out.file.lines_read = static_cast<std::size_t>(c.sample_messages);
  out.file.lines_skipped = static_cast<std::size_t>(c.decode_errors + c.duplicates + c.quantity_errors);
  for (const RefitRun& r : out.runs) {
    out.file.runs.push_back(r.fit);
    if (r.fit.best.empty())
      out.file.failures.push_back(fmt::format("SPINDOWN.{}.SAMPLE: run {}: no model converged", r.bench,
                                              r.fit.run.number));
  }
  if (out.runs_fitted == 0)
    out.file.failures.push_back(c.samples > 0 ? fmt::format("no spin-down run found in {} samples", c.samples)
                                              : std::string("no samples on SPINDOWN.<bench>.SAMPLE channels"));
  return out;
}

Json refit_file_json(const LogRefit& refit, const ReportOptions& opt) {
  Json j = file_fit_json(refit.file, opt);
  Json& runs = j["runs"];
  for (std::size_t i = 0; i < refit.runs.size() && i < runs.size(); ++i)
    tag_run_json(runs[i], {refit.runs[i].bench, refit.runs[i].first_seq, refit.runs[i].last_seq});
  return j;
}

void setup_refit(CLI::App& app) {
  auto opt = std::make_shared<RefitCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "refit", "Refit LCM logs exactly as spindown-fitter did live (same runs, same numbers); --compare checks it");
  sub->footer(
      "Reads each log in its own order with its own timestamps (never file:// replay). Runs are listed by bench, "
      "then run number; in JSON each run also has bench.id, first_seq and last_seq.\n"
      "Exit codes: 0 ok, 1 a log or run could not be used or --compare found a difference, 2 bad usage.");
  sub->add_option("LOG", opt->logs, "LCM event log(s) (spindown-logger, lcm-logger)")->required();
  sub->add_flag("--json", opt->json, "Print one JSON object {\"files\":[{\"runs\":[…]}]} instead of tables");
  sub->add_option("--bench", opt->bench_regex, "Only benches whose id matches this regex (default all)");
  sub->add_option("--models", opt->models, "Models to fit: viscous,coulomb,combined (default all)")
      ->delimiter(',')
      ->allow_extra_args(false);
  sub->add_flag("--lab-units", opt->lab_units, "Also give the lab's units");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");
  sub->add_flag("--no-progress", opt->no_progress, "No progress line on a terminal (there is none when stderr is not one)");
  auto* live = sub->add_flag("--live", opt->live, "Print the FIT messages recorded in the log instead of refitting");
  sub->add_flag("--compare", opt->compare,
                "Refit and compare with the recorded FIT messages, timing fields aside (exit 1 on a difference)")
      ->excludes(live);
  auto* j = sub->add_option("--inertia", opt->inertia_kg_m2, "J (kg·m²) for benches without CONFIG")
                ->check(CLI::PositiveNumber)
                ->group("Bench");
  auto* kb = sub->add_option("--kb", opt->kb_v_s_per_rad, "K_b (V·s/rad) for benches without CONFIG")
                 ->check(CLI::PositiveNumber)
                 ->group("Bench");
  auto* kv = sub->add_option("--speed-constant", opt->speed_constant_rpm_per_v, "K_b from a speed constant (rpm/V)")
                 ->check(CLI::PositiveNumber)
                 ->excludes(kb)
                 ->group("Bench");
  sub->add_option("--max-benches", opt->max_benches,
                  "Benches held at once, as the live spindown-fitter --max-benches (evictions are replayed too)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--admit-rate", opt->admit_rate_hz, "New benches admitted per second, as spindown-fitter --admit-rate")
      ->check(CLI::PositiveNumber);
  sub->add_option("--silent", opt->silent_s,
                  "Seconds without samples (log time) that close a bench's open run, as spindown-fitter --silent")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--ignore-config", opt->ignore_config, "Use --inertia/--kb (or the lab's) even where CONFIG says otherwise")
      ->group("Bench");
  sub->callback([opt, j, kb, kv]() {
    opt->inertia_given = j->count() > 0;
    opt->kb_given = kb->count() > 0;
    opt->speed_constant_given = kv->count() > 0;
    const int code = run_refit(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_refit(const RefitCommandOptions& o) {
  const FitterOptions fopt = fitter_options(o);
  ReportOptions report;
  report.lab_units = o.lab_units;
  report.max_diagnostics = o.verbose ? 0 : 8;
  report.diagnostics_in_text = false;
  bool ok = true;
  Json files = Json::array();
  const bool show_progress = !o.no_progress && ProgressReporter::is_terminal(STDERR_FILENO);
  const bool stream = !o.live && !o.compare;  // runs formatted as fitted, not kept (memory flat)
  bool first_file = true;
  for (const auto& path : o.logs) {
    // On a terminal only (never in pipes or files), throttled, erased before anything is printed.
    ProgressReporter progress(STDERR_FILENO, show_progress);
    // Each bench's runs, formatted as they are fitted; printed by bench (first appearance) once
    // the log is done, as the order contract wants.
    std::vector<std::pair<std::string, std::unique_ptr<RunSpool>>> spools;
    std::string run_text;  // reused: one run's JSON at a time
    auto each_run = [&](RefitRun&& run) {
      RunSpool* spool = nullptr;
      for (auto& [bench, sp] : spools)
        if (bench == run.bench) spool = sp.get();
      if (!spool) spool = spools.emplace_back(run.bench, std::make_unique<RunSpool>()).second.get();
      if (o.json) {
        // The run as refit_file_json() lists it, written straight to text (no document).
        const RunTags tags{run.bench, run.first_seq, run.last_seq};
        run_text.assign(",\n        ");
        append_run_fit_json_text(run_text, run.fit, report, 8, &tags);
        spool->add(run_text);
      } else {
        spool->add(fmt::format("\n-- bench {} (J/K_b: {})\n", run.bench, run.bench_source) +
                   format_run_fit(run.fit, report));
      }
    };
    LogRefit r = refit_log(
        path, fopt, o.live || o.compare, {},
        [&](std::int64_t done, std::int64_t total, std::size_t runs) {
          progress.update(done, total, "refit", fmt::format("{} run{} fitted  {}", runs, runs == 1 ? "" : "s", path));
        },
        stream ? RefitRunFn(each_run) : RefitRunFn());
    progress.finish();
    // Problems on stderr, as `spindown fit` says them; with --live or --compare the file's failures
    // are not the point (the comparison's counts are).
    report_file_problems(std::cerr, path, r.file.diagnostics,
                         o.live || o.compare ? std::vector<std::string>{} : r.file.failures, o.verbose,
                         report.max_diagnostics);

    if (o.live || o.compare) {
      // Recorded results in log order; the refit's likewise.
      std::vector<std::pair<std::string, Json>> live;
      const std::regex wanted(o.bench_regex);
      for (const fit_t& m : r.live) {
        if (!std::regex_match(m.bench, wanted)) continue;
        std::string why;
        if (auto jf = fit_message_json(m, report, &why))
          live.emplace_back(m.bench, without_timing_fields(std::move(*jf)));
        else
          std::cerr << path << ": warning: " << why << '\n';
      }
      if (o.live) {
        if (live.empty()) {
          std::cerr << path << ": error: no SPINDOWN.<bench>.FIT messages recorded in this log\n";
          ok = false;
        }
        Json runs = Json::array();
        for (auto& [bench, jr] : live) runs.push_back(jr);
        if (o.json) {
          files.push_back(Json{{"file", path}, {"runs", std::move(runs)}});
        } else {
          std::cout << fmt::format("== {}: {} FIT messages recorded\n", path, live.size());
          for (const fit_t& m : r.live)
            if (auto f = from_fit_message(m))
              std::cout << fmt::format("\n-- bench {} (live, latency {:.1f} ms, J/K_b: {})\n", m.bench,
                                       1e3 * m.latency_s, m.bench_source)
                        << format_run_fit(*f, report);
        }
        continue;
      }
      // --compare: a live FIT and a refitted run are the same run when they are on the same bench
      // and their fitted windows overlap (run numbers restart with the fitter; the device time
      // does not), the largest overlap first.
      const Json refit = refit_file_json(r, report);
      std::size_t same = 0, differ = 0, missing_live = 0, missing_refit = 0;
      std::vector<bool> live_paired(live.size(), false);
      for (std::size_t i = 0; i < r.runs.size(); ++i) {
        const RefitRun& ours = r.runs[i];
        const Json jr = without_timing_fields(refit["runs"][i]);
        std::size_t best = live.size();
        double best_overlap = 0;
        for (std::size_t k = 0; k < live.size(); ++k) {
          if (live_paired[k] || live[k].first != ours.bench) continue;
          const double overlap = window_overlap_s(ours.fit.run, live[k].second);
          if (overlap > best_overlap) best = k, best_overlap = overlap;
        }
        const std::string name = fmt::format("{} run {} (cut at {:.3f} s)", ours.bench, ours.fit.run.number,
                                             ours.fit.run.t_cut_s);
        if (best == live.size()) {
          ++missing_live;
          std::cout << fmt::format("{}: {}: refit found it, no live FIT recorded\n", path, name);
          continue;
        }
        live_paired[best] = true;
        // The run number is the fitter's count since it started, not the run's identity.
        Json a = jr, b = live[best].second;
        a.erase("run");
        b.erase("run");
        const std::string d = first_difference(a, b, "run");
        if (d.empty()) {
          ++same;
          continue;
        }
        ++differ;
        const bool live_partial = b.value("lead_in", "") == "none", ours_partial = ours.fit.run.partial();
        std::cout << fmt::format("{}: {}: differs: {}{}\n", path, name, d,
                                 live_partial && !ours_partial
                                     ? " (live joined this run mid-coast: the fitter started or took the bench "
                                       "in after its cut; the log holds the whole run)"
                                     : "");
      }
      for (std::size_t k = 0; k < live.size(); ++k)
        if (!live_paired[k]) {
          ++missing_refit;
          std::cout << fmt::format("{}: {} live run {} (cut at {:.3f} s): live FIT recorded, the refit did not find "
                                   "this run\n",
                                   path, live[k].first, live[k].second.value("run", 0),
                                   number_in(live[k].second, "t_cut_s"));
        }
      std::cout << fmt::format("{}: {} runs refitted, {} live FIT messages: {} identical, {} different, {} only "
                               "refitted, {} only live\n",
                               path, r.runs.size(), live.size(), same, differ, missing_live, missing_refit);
      if (differ || missing_live || missing_refit || live.empty()) ok = false;
      continue;
    }

    ok = ok && r.file.usable();
    // Spools by bench in order of first appearance (a bench never seen on SAMPLE/CONFIG last).
    std::vector<RunSpool*> ordered;
    for (const auto& id : r.bench_order)
      for (auto& [bench, sp] : spools)
        if (bench == id) ordered.push_back(sp.get());
    for (auto& [bench, sp] : spools)
      if (std::find(r.bench_order.begin(), r.bench_order.end(), bench) == r.bench_order.end())
        ordered.push_back(sp.get());
    if (o.json) {
      // The file's object as refit_file_json() gives it, its runs spliced in from the spools;
      // the same bytes as dumping the whole document at once.
      constexpr std::string_view hole = "(runs spliced here)";  // printed by dump() as it is
      Json file = refit_file_json(r, report);
      file["runs"] = hole;
      const std::string text = indented(dump_json(file), 4);
      const std::string key = fmt::format("\n      \"runs\": \"{}\"", hole);
      const std::size_t at = text.find(key);
      std::cout << (first_file ? "{\n  \"files\": [\n" : ",\n") << std::string_view(text).substr(0, at);
      first_file = false;
      if (ordered.empty()) {
        std::cout << "\n      \"runs\": []";
      } else {
        std::cout << "\n      \"runs\": [\n";
        for (std::size_t i = 0; i < ordered.size(); ++i) ordered[i]->copy_to(std::cout, i == 0 ? 2 : 0);
        std::cout << "\n      ]";
      }
      std::cout << std::string_view(text).substr(at + key.size());
    } else {
      const std::size_t runs = r.runs_fitted, benches = ordered.size();
      std::cout << fmt::format("== {}: {} samples from {} messages ({} skipped), {} run{} fitted on {} bench{}\n",
                               path, r.file.samples, r.file.lines_read, r.file.lines_skipped, runs,
                               runs == 1 ? "" : "s", benches, benches == 1 ? "" : "es");
      for (RunSpool* spool : ordered) spool->copy_to(std::cout, 0);
    }
    std::cout.flush();
  }
  // replace: bytes that are not UTF-8 (a config string in the log) never abort the output.
  if (o.json && o.live)
    std::cout << Json{{"files", std::move(files)}}.dump(2, ' ', false, Json::error_handler_t::replace) << std::endl;
  else if (o.json && stream && !first_file)
    std::cout << "\n  ]\n}" << std::endl;
  return ok ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
