#include "refit_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <iostream>
#include <limits>
#include <memory>
#include <regex>
#include <string_view>
#include <unistd.h>
#include <vector>

#include "exit_codes.hpp"
#include "file_problems.hpp"
#include "spindown/bench.hpp"
#include "spindown/effects.hpp"
#include "spindown/explain_message.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/health_report.hpp"
#include "spindown/log_lab.hpp"
#include "spindown/progress.hpp"

namespace spindown::cli {

namespace {

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
  // Numbers by value: a document read from text holds 854 as unsigned, one built in code as a
  // signed integer; the same number either way.
  if (a.type() != b.type() && !(a.is_number() && b.is_number()))
    return fmt::format("{}: {} vs {}", path, a.dump(), b.dump());
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

// The live fitter's options for the log. J and K_b: what the command line and the bench files name
// wins over the CONFIG (FitterOptions::named), as in `spindown fit`; with --compare they are the
// live fitter's instead (the flags its defaults for benches without CONFIG, the files its health
// references), so that the comparison sets like beside like.
FitterOptions fitter_options(const RefitCommandOptions& o, const BenchFiles& files) {
  FitterOptions f;
  f.bench_regex = o.bench_regex;
  f.ignore_config = o.ignore_config;
  f.max_benches = o.max_benches;
  f.admit_rate_hz = o.admit_rate_hz;
  f.silent_s = o.silent_s;
  f.max_rate_hz = 0;  // a log is read as fast as the disk allows; live caps were applied live
  f.gate = gate_options_from(o.input.lab);
  f.gate.replay_window_s = o.replay_window_s;
  f.stream.takeover_s = o.takeover_s;
  const BenchChoice named = bench_choice_from(o.input);
  for (const auto& [bench, file] : files.files) f.health.emplace(bench, file.health);
  if (o.compare) {
    f.default_bench = named.given;
  } else {
    f.named = named;
    f.bench_files = files.files;
  }
  if (!o.models.empty()) f.models = models_from(o.models);
  std::string why;
  if (o.explain || o.compare) {
    f.explain_base = parse_effect_list(o.explain_base, &why);
    if (f.explain_base.empty()) throw CLI::ValidationError("--explain-base: " + why);
  }
  if (!f.is_valid(&why)) throw CLI::ValidationError(why);
  return f;
}

// The recorded FIT messages of a session (recorded_fits), each with its bench and the fitter session
// that published it: a run number counts from that session's start.
struct LiveFit {
  std::string bench;
  Json json;
  std::int64_t session = 0;
};
using LiveFits = std::vector<LiveFit>;

// --compare's EXPLAIN: each refitted run's EXPLAIN against the recorded one of the same run, every
// field but the time; one line of counts. False when one differs. The same run as the FITs are
// paired (partners: the live FIT of each refitted run): the EXPLAIN of that FIT's bench, run number
// and fitter session (run numbers restart with the fitter, so a number alone names several runs).
bool compare_explains(const std::string& path, const LogRefit& r, const std::regex& wanted, const LiveFits& fits,
                      const std::vector<std::size_t>& partners) {
  std::vector<const explain_t*> live;
  for (const explain_t& m : r.live_explains)
    if (std::regex_match(m.bench, wanted)) live.push_back(&m);
  std::vector<bool> paired(live.size(), false);
  std::size_t refitted = 0, same = 0, differ = 0, only_refit = 0;
  const auto close = [](double a, double b) {
    return a == b || (std::isnan(a) && std::isnan(b)) || std::abs(a - b) <= 1e-9 * std::max(std::abs(a), std::abs(b));
  };
  for (std::size_t i = 0; i < r.runs.size(); ++i) {
    const RefitRun& run = r.runs[i];
    if (!run.explain) continue;
    ++refitted;
    const explain_t ours = to_explain_message(*run.explain, run.bench, 0);
    std::size_t k = live.size();
    if (i < partners.size() && partners[i] < fits.size()) {
      const LiveFit& fit = fits[partners[i]];
      const int number = fit.json.value("run", 0);
      k = 0;
      while (k < live.size() && (paired[k] || live[k]->bench != run.bench || live[k]->run != number ||
                                 live[k]->source_session != fit.session))
        ++k;
    }
    if (k == live.size()) {
      ++only_refit;
      continue;
    }
    paired[k] = true;
    const explain_t& theirs = *live[k];
    std::string d;
    if (ours.base != theirs.base) d = "base";
    else if (ours.step_added != theirs.step_added) d = "steps";
    else if (ours.final_effects != theirs.final_effects) d = "final model";
    else if (!close(ours.rmse_base, theirs.rmse_base) || !close(ours.rmse_final, theirs.rmse_final)) d = "RMSE";
    else if (ours.param_name != theirs.param_name) d = "parameters";
    else
      for (std::size_t j = 0; j < ours.param_value.size() && d.empty(); ++j)
        if (!close(ours.param_value[j], theirs.param_value[j]) || !close(ours.param_stderr[j], theirs.param_stderr[j]))
          d = "parameter " + ours.param_name[j];
    if (d.empty()) {
      ++same;
    } else {
      ++differ;
      std::cout << fmt::format("{}: {} run {}: EXPLAIN differs: {} (live final {}, RMSE {:.6g}; refit final {}, RMSE {:.6g})\n",
                               path, run.bench, ours.run, d, fmt::join(theirs.final_effects, "+"), theirs.rmse_final,
                               fmt::join(ours.final_effects, "+"), ours.rmse_final);
    }
  }
  const std::size_t only_live = static_cast<std::size_t>(std::count(paired.begin(), paired.end(), false));
  if (live.empty()) {
    std::cout << fmt::format("{}: EXPLAIN: {} runs explained, no live EXPLAIN messages recorded (the live fitter ran "
                             "with --no-explain): nothing to compare\n",
                             path, refitted);
    return true;
  }
  std::cout << fmt::format("{}: EXPLAIN: {} runs explained, {} live EXPLAIN messages: {} identical, {} different, {} only "
                           "refitted, {} only live\n",
                           path, refitted, live.size(), same, differ, only_refit, only_live);
  return differ == 0 && only_refit == 0 && only_live == 0;
}

// Whether the command line or a bench file names J or K_b (what --compare leaves to the CONFIG).
bool names_bench(const RefitCommandOptions& o, const BenchFiles& files) {
  const InputOptions& i = o.input;
  if (i.inertia_given || i.flywheel_given || i.kb_given || i.speed_constant_given) return true;
  return std::any_of(files.files.begin(), files.files.end(),
                     [](const auto& f) { return f.second.sets_inertia || f.second.sets_kb; });
}

// A health verdict's level in capitals ("CHECK"), or "none".
std::string level_of(const Json& run) {
  const auto h = run.find("health");
  if (h == run.end() || !h->is_object()) return "none";
  std::string level = h->value("level", "?");
  for (char& c : level) c = c == '_' ? ' ' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return level;
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

// Why a refitted run and the live FIT paired with it differ, in words (what a lab sees: a run
// joined mid-coast, a run split at a silence or a gap, a cut one side invented, samples the live
// fitter never got); "" when nothing explains it beyond the numbers.
std::string why_they_differ(const Run& ours, std::int64_t ours_samples, const Json& live) {
  const bool live_partial = live.value("lead_in", "") == "none", ours_partial = ours.partial();
  const double live_cut = number_in(live, "t_cut_s"), live_end = number_in(live, "t_end_s");
  const std::string live_end_name = live.value("end", "");
  const double tol = 1.5 * std::max(ours.period_s, 1e-3);
  if (live_partial && !ours_partial)
    return "partial: live joined this run mid-coast (the fitter started, took the bench in, or resumed after a "
           "silence after its cut); the log holds the whole run";
  if (ours_partial && !live_partial)
    return "partial: the refit joined this run mid-coast (the log, or the first file of this session, starts after "
           "its cut; give the refit the file before it too)";
  if (!live_partial && !ours_partial && std::isfinite(live_cut) && std::abs(live_cut - ours.t_cut_s) > tol)
    return live_cut > ours.t_cut_s
               ? fmt::format("invented cut: live put a cut at {:.3f} s inside the coast the log shows cut at {:.3f} s "
                             "(live missed samples there: an outage, a frozen or restarted fitter)",
                             live_cut, ours.t_cut_s)
               : fmt::format("invented cut: the refit put a cut at {:.3f} s inside the coast live saw cut at {:.3f} s",
                             ours.t_cut_s, live_cut);
  if (live_end_name != end_name(ours.end) && std::isfinite(live_end) && std::isfinite(ours.t_end_s) &&
      std::abs(live_end - ours.t_end_s) > tol)
    return live_end < ours.t_end_s
               ? fmt::format("split: live closed this run at {:.3f} s ({}) and the rest of the coast was apart; the "
                             "refit ends it at {:.3f} s ({})",
                             live_end, live_end_name, ours.t_end_s, end_name(ours.end))
               : fmt::format("split: the refit closed this run at {:.3f} s ({}); live went on to {:.3f} s ({})",
                             ours.t_end_s, end_name(ours.end), live_end, live_end_name);
  if (const auto it = live.find("samples"); it != live.end() && it->is_number() && it->get<std::int64_t>() != ours_samples)
    return fmt::format("samples: live fitted {} samples, the refit {} (samples the live fitter did not get, or the "
                       "logger did not)",
                       it->get<std::int64_t>(), ours_samples);
  return {};
}


// One session's name in the output: its file, or its first file and how many more.
std::string session_name(const std::vector<std::string>& session) {
  return session.size() == 1
             ? session.front()
             : fmt::format("{} + {} more (one session, in time order)", session.front(), session.size() - 1);
}

// Each bench's runs of one session, formatted as they are fitted; printed by bench (first
// appearance) once the log is done, as the order contract wants.
class SessionSpools {
 public:
  SessionSpools(const RefitCommandOptions& o, const ReportOptions& report) : o_(o), report_(report) {}

  void add(RefitRun&& run) {
    if (run.explain) explains_.push_back(Json::parse(explain_run_json(*run.explain, run.bench, report_).dump()));
    RunSpool& spool = spool_of(run.bench);
    if (o_.json) {
      // The run as refit_file_json() lists it, written straight to text (no document).
      const RunTags tags{run.bench, run.first_seq, run.last_seq};
      run_text_.assign(",\n        ");
      append_run_fit_json_text(run_text_, run.fit, report_, 8, &tags, run.health ? &*run.health : nullptr);
      spool.add(run_text_);
    } else {
      spool.add(fmt::format("\n-- bench {} (J/K_b: {})\n", run.bench, run.bench_source) +
                format_run_fit(run.fit, report_) + (run.health ? format_health_verdict(*run.health) : std::string()));
    }
  }

  // The spools by bench in order of first appearance (a bench never seen on SAMPLE/CONFIG last).
  std::vector<RunSpool*> in_order(const std::vector<std::string>& bench_order) {
    std::vector<RunSpool*> ordered;
    for (const auto& id : bench_order)
      for (auto& [bench, sp] : spools_)
        if (bench == id) ordered.push_back(sp.get());
    for (auto& [bench, sp] : spools_)
      if (std::find(bench_order.begin(), bench_order.end(), bench) == bench_order.end()) ordered.push_back(sp.get());
    return ordered;
  }

  // --explain: each run's EXPLAIN, as spindown explain --json gives a run.
  Json take_explains() { return std::move(explains_); }

 private:
  RunSpool& spool_of(const std::string& bench) {
    for (auto& [id, sp] : spools_)
      if (id == bench) return *sp;
    return *spools_.emplace_back(bench, std::make_unique<RunSpool>()).second;
  }

  const RefitCommandOptions& o_;
  const ReportOptions& report_;
  std::vector<std::pair<std::string, std::unique_ptr<RunSpool>>> spools_;
  std::string run_text_;  // reused: one run's JSON at a time
  Json explains_ = Json::array();
};

// The recorded FIT messages of the wanted benches as JSON without the timing fields, in log
// order, each with its bench id; one the report cannot read is a warning on stderr.
LiveFits recorded_fits(const std::string& path, const LogRefit& r, const std::string& bench_regex,
                       const ReportOptions& report) {
  LiveFits live;
  const std::regex wanted(bench_regex);
  for (const fit_t& m : r.live) {
    if (!std::regex_match(m.bench, wanted)) continue;
    std::string why;
    if (auto jf = fit_message_json(m, report, &why))
      live.push_back({m.bench, without_timing_fields(std::move(*jf)), m.source_session});
    else
      std::cerr << path << ": warning: " << why << '\n';
  }
  return live;
}

// --compare for one session: a live FIT and a refitted run are the same run when they are on the
// same bench and their fitted windows overlap (run numbers restart with the fitter; the device
// time does not), the largest overlap first. Each difference is a line on stdout, then a line of
// counts.
class FitComparison {
 public:
  FitComparison(const std::string& path, const LogRefit& r, const LiveFits& live, const ReportOptions& report)
      : path_(path), r_(r), live_(live), report_(report), live_paired_(live.size(), false),
        partner_(r.runs.size(), live.size()) {}

  // After run(): for each refitted run, the index of the live FIT paired with it (live.size(): none).
  const std::vector<std::size_t>& partners() const { return partner_; }

  // False when a run differs or is on one side only, or nothing was recorded.
  bool run() {
    const Json refit = refit_file_json(r_, report_);
    for (std::size_t i = 0; i < r_.runs.size(); ++i) {
      const RefitRun& ours = r_.runs[i];
      const std::string name =
          fmt::format("{} run {} (cut at {:.3f} s)", ours.bench, ours.fit.run.number, ours.fit.run.t_cut_s);
      const std::size_t k = live_partner(ours);
      if (k == live_.size()) {
        refit_only(ours, name);
        continue;
      }
      live_paired_[k] = true;
      partner_[i] = k;
      compare_pair(ours, without_timing_fields(refit["runs"][i]), live_[k].json, name);
    }
    for (std::size_t k = 0; k < live_.size(); ++k)
      if (!live_paired_[k]) live_only(k);
    print_counts();
    return !(differ_ || verdict_differ_ || missing_live_ || missing_refit_ || live_.empty());
  }

 private:
  // The unpaired live FIT of the run's bench whose window overlaps the run's most; none: size().
  std::size_t live_partner(const RefitRun& ours) const {
    std::size_t best = live_.size();
    double best_overlap = 0;
    for (std::size_t k = 0; k < live_.size(); ++k) {
      if (live_paired_[k] || live_[k].bench != ours.bench) continue;
      const double overlap = window_overlap_s(ours.fit.run, live_[k].json);
      if (overlap > best_overlap) best = k, best_overlap = overlap;
    }
    return best;
  }

  void refit_only(const RefitRun& ours, const std::string& name) {
    ++missing_live_;
    std::string why;
    for (const auto& [bench, theirs, session] : live_)
      if (bench == ours.bench && window_overlap_s(ours.fit.run, theirs) > 0) {
        why = fmt::format(" (split: it lies inside live run {} (cut at {:.3f} s), which the refit splits here)",
                          theirs.value("run", 0), number_in(theirs, "t_cut_s"));
        break;
      }
    if (why.empty() && ours.fit.run.end == Run::End::end_of_data)
      why = " (split: the log ends during this run, and its live FIT, published when it ended, is in the log "
            "after it: refit the session's files together)";
    std::cout << fmt::format("{}: {}: refit found it, no live FIT recorded{}\n", path_, name, why);
  }

  void compare_pair(const RefitRun& ours, const Json& jr, const Json& theirs, const std::string& name) {
    // The run number is the fitter's count since it started, not the run's identity. The
    // numbers first; a health verdict is compared on its own, since one side may have had a
    // bench file and the other not.
    Json a = jr, b = theirs;
    a.erase("run");
    b.erase("run");
    const std::string ours_level = level_of(a), live_level = level_of(b);
    Json ours_health = a.contains("health") ? a["health"] : Json(), live_health = b.contains("health") ? b["health"] : Json();
    a.erase("health");
    b.erase("health");
    const std::string d = first_difference(a, b, "run");
    if (!d.empty()) {
      ++differ_;
      const std::string why = why_they_differ(ours.fit.run, jr.value("samples", std::int64_t{0}), b);
      std::cout << fmt::format("{}: {}: differs: {}{}\n", path_, name, d, why.empty() ? "" : " (" + why + ")");
      return;
    }
    ++same_;
    compare_health(ours, ours_health, live_health, ours_level, live_level, name);
  }

  // Identical numbers: a health verdict on one side only, or another one, says the bench files differ.
  void compare_health(const RefitRun& ours, const Json& ours_health, const Json& live_health,
                      const std::string& ours_level, const std::string& live_level, const std::string& name) {
    if (live_health.is_null() && ours_health.is_null()) return;
    if (ours_health.is_null()) {
      ++verdict_live_only_;
      std::cout << fmt::format("{}: {}: identical numbers; health {} live, none here: the live fitter had a "
                               "bench file for bench {}, this refit has none (give it with --bench-config)\n",
                               path_, name, live_level, ours.bench);
    } else if (live_health.is_null()) {
      ++verdict_refit_only_;
      std::cout << fmt::format("{}: {}: identical numbers; health {} here, none live: the live fitter had no "
                               "bench file for bench {}\n",
                               path_, name, ours_level, ours.bench);
    } else if (const std::string hd = first_difference(ours_health, live_health, "run.health"); !hd.empty()) {
      ++verdict_differ_;
      std::cout << fmt::format("{}: {}: identical numbers, but health {} here against {} live ({}): this "
                               "bench file is not the one the live fitter had\n",
                               path_, name, ours_level, live_level, hd);
    }
  }

  void live_only(std::size_t k) {
    const auto& [bench, theirs, session] = live_[k];
    ++missing_refit_;
    // Part of a refitted run already paired: live split that run in two.
    std::string why;
    for (const RefitRun& ours : r_.runs)
      if (ours.bench == bench && window_overlap_s(ours.fit.run, theirs) > 0) {
        const bool partial = theirs.value("lead_in", "") == "none";
        why = fmt::format(" (split: it lies inside refit run {} (cut at {:.3f} s); live {}", ours.fit.run.number,
                          ours.fit.run.t_cut_s,
                          partial ? "published this part of it as a partial run of its own)"
                                  : "gave this part of it a cut of its own: an invented cut)");
        break;
      }
    std::cout << fmt::format("{}: {} live run {} (cut at {:.3f} s): live FIT recorded, the refit did not find "
                             "this run{}\n",
                             path_, bench, theirs.value("run", 0), number_in(theirs, "t_cut_s"), why);
  }

  void print_counts() const {
    std::string verdicts;
    if (verdict_live_only_)
      verdicts += fmt::format("; {} with a health verdict live only (the live fitter had a bench file, this refit "
                              "none)",
                              verdict_live_only_);
    if (verdict_refit_only_)
      verdicts += fmt::format("; {} with a health verdict here only (the live fitter had no bench file)",
                              verdict_refit_only_);
    if (verdict_differ_) verdicts += fmt::format("; {} with another health verdict (another bench file)", verdict_differ_);
    std::cout << fmt::format("{}: {} runs refitted, {} live FIT messages: {} identical, {} different, {} only "
                             "refitted, {} only live{}\n",
                             path_, r_.runs.size(), live_.size(), same_, differ_, missing_live_, missing_refit_, verdicts);
  }

  const std::string& path_;
  const LogRefit& r_;
  const LiveFits& live_;
  const ReportOptions& report_;
  std::vector<bool> live_paired_;
  std::vector<std::size_t> partner_;
  std::size_t same_ = 0, differ_ = 0, missing_live_ = 0, missing_refit_ = 0;
  std::size_t verdict_live_only_ = 0, verdict_refit_only_ = 0, verdict_differ_ = 0;
};

// `spindown refit`: each session refitted (or its recorded FITs listed, or compared), printed as
// it is done; the state the sessions share (the options, whether all went well, the JSON's files).
class RefitCommand {
 public:
  explicit RefitCommand(const RefitCommandOptions& o)
      : o_(o),
        bench_files_(bench_files_from(o.input, std::cerr)),
        fopt_(fitter_options(o, bench_files_)),
        show_progress_(!o.no_progress && ProgressReporter::is_terminal(STDERR_FILENO)),
        stream_(!o.live && !o.compare) {  // runs formatted as fitted, not kept (memory flat)
    if (o.compare && names_bench(o, bench_files_))
      std::cerr << "spindown refit --compare: J and K_b as the live fitter chose them (the log's CONFIG, else the "
                   "command line's as its defaults), so that like is compared with like; a bench file gives the "
                   "health references only\n";
    report_.lab_units = o.lab_units;
    report_.max_diagnostics = o.verbose ? 0 : 8;
    report_.diagnostics_in_text = false;
  }

  int run() {
    // Logs given together are read as sessions in time order: a logger's rotated files are one
    // session, so a run across a file boundary is whole, as it was live.
    const std::vector<std::vector<std::string>> sessions =
        o_.logs.size() > 1 ? log_sessions(o_.logs) : std::vector<std::vector<std::string>>{o_.logs};
    for (const auto& session : sessions) refit_session(session);
    // replace: bytes that are not UTF-8 (a config string in the log) never abort the output.
    if (o_.json && o_.live)
      std::cout << Json{{"files", std::move(live_files_)}}.dump(2, ' ', false, Json::error_handler_t::replace)
                << std::endl;
    else if (o_.json && stream_ && !first_file_)
      std::cout << "\n  ]\n}" << std::endl;
    return ok_ ? exit_ok : exit_unusable;
  }

 private:
  void refit_session(const std::vector<std::string>& session) {
    const std::string path = session_name(session);
    SessionSpools spools(o_, report_);
    const LogRefit r = read_session(session, path, spools);
    // Problems on stderr, as `spindown fit` says them; with --live or --compare the file's failures
    // are not the point (the comparison's counts are).
    report_file_problems(std::cerr, path, r.file.diagnostics,
                         o_.live || o_.compare ? std::vector<std::string>{} : r.file.failures, o_.verbose,
                         report_.max_diagnostics);
    if (o_.live) {
      print_recorded(path, r, recorded_fits(path, r, o_.bench_regex, report_));
      return;
    }
    if (o_.compare) {
      // Recorded results in log order; the refit's likewise.
      const LiveFits live = recorded_fits(path, r, o_.bench_regex, report_);
      FitComparison fits(path, r, live, report_);
      if (!fits.run()) ok_ = false;
      if (!compare_explains(path, r, std::regex(o_.bench_regex), live, fits.partners())) ok_ = false;
      return;
    }
    ok_ = ok_ && r.file.usable();
    const std::vector<RunSpool*> ordered = spools.in_order(r.bench_order);
    if (o_.json)
      print_refit_json(r, ordered, spools.take_explains());
    else
      print_refit_text(path, r, ordered);
    std::cout.flush();
  }

  // The lab whose messages are refitted: --lab (or $SPINDOWN_LAB) when given, else the lab the
  // log's own logger served (log_lab.hpp), with the group and port it listened on: a PC serving
  // two labs records both, and the default lab name would refit the other lab's benches.
  FitterOptions session_options(const std::string& first_file, const std::string& path) const {
    FitterOptions f = fopt_;
    if (!o_.input.lab.lab.empty() || std::getenv("SPINDOWN_LAB")) return f;
    const std::optional<LogLab> lab = log_lab(first_file);
    if (!lab || (lab->lab == f.gate.lab && lab->sent_to == f.gate.sent_to)) return f;
    f.gate.lab = lab->lab;
    f.gate.sent_to = lab->sent_to;
    std::cerr << fmt::format("{}: recorded by the logger of lab '{}'{}: that lab's messages are refitted, others "
                             "counted and named (--lab to choose)\n",
                             path, lab->lab, lab->sent_to.empty() ? std::string() : " on " + lab->sent_to);
    return f;
  }

  // The session through the live fitter's core, its runs spooled as they are fitted (when streaming).
  LogRefit read_session(const std::vector<std::string>& session, const std::string& path, SessionSpools& spools) {
    // On a terminal only (never in pipes or files), throttled, erased before anything is printed.
    ProgressReporter progress(STDERR_FILENO, show_progress_);
    const FitterOptions options = session_options(session.front(), path);
    LogRefit r = refit_log_session(
        session, options, o_.live || o_.compare, {},
        [&](std::int64_t done, std::int64_t total, std::size_t runs) {
          progress.update(done, total, "refit", fmt::format("{} run{} fitted  {}", runs, runs == 1 ? "" : "s", path));
        },
        stream_ ? RefitRunFn([&spools](RefitRun&& run) { spools.add(std::move(run)); }) : RefitRunFn());
    progress.finish();
    return r;
  }

  // --live: the FIT messages recorded in the session, as text or as the JSON's next file.
  void print_recorded(const std::string& path, const LogRefit& r, const LiveFits& live) {
    if (live.empty()) {
      std::cerr << path << ": error: no SPINDOWN.<bench>.FIT messages recorded in this log\n";
      ok_ = false;
    }
    if (o_.json) {
      Json runs = Json::array();
      for (const LiveFit& l : live) runs.push_back(l.json);
      live_files_.push_back(Json{{"file", path}, {"runs", std::move(runs)}});
      return;
    }
    std::cout << fmt::format("== {}: {} FIT messages recorded\n", path, live.size());
    for (const fit_t& m : r.live)
      if (auto f = from_fit_message(m))
        std::cout << fmt::format("\n-- bench {} (live, latency {:.1f} ms, J/K_b: {})\n", m.bench, 1e3 * m.latency_s,
                                 m.bench_source)
                  << format_run_fit(*f, report_);
  }

  // The file's object as refit_file_json() gives it, its runs spliced in from the spools; the
  // same bytes as dumping the whole document at once.
  void print_refit_json(const LogRefit& r, const std::vector<RunSpool*>& ordered, Json explains) {
    constexpr std::string_view hole = "(runs spliced here)";  // printed by dump() as it is
    Json file = refit_file_json(r, report_);
    if (o_.explain) file["explains"] = std::move(explains);
    file["runs"] = hole;
    const std::string text = indented(dump_json(file), 4);
    const std::string key = fmt::format("\n      \"runs\": \"{}\"", hole);
    const std::size_t at = text.find(key);
    std::cout << (first_file_ ? "{\n  \"files\": [\n" : ",\n") << std::string_view(text).substr(0, at);
    first_file_ = false;
    if (ordered.empty()) {
      std::cout << "\n      \"runs\": []";
    } else {
      std::cout << "\n      \"runs\": [\n";
      for (std::size_t i = 0; i < ordered.size(); ++i) ordered[i]->copy_to(std::cout, i == 0 ? 2 : 0);
      std::cout << "\n      ]";
    }
    std::cout << std::string_view(text).substr(at + key.size());
  }

  void print_refit_text(const std::string& path, const LogRefit& r, const std::vector<RunSpool*>& ordered) {
    const std::size_t runs = r.runs_fitted, benches = ordered.size();
    std::cout << fmt::format("== {}: {} samples from {} messages ({} skipped), {} run{} fitted on {} bench{}\n", path,
                             r.file.samples, r.file.lines_read, r.file.lines_skipped, runs, runs == 1 ? "" : "s",
                             benches, benches == 1 ? "" : "es");
    for (RunSpool* spool : ordered) spool->copy_to(std::cout, 0);
  }

  const RefitCommandOptions& o_;
  const BenchFiles bench_files_;
  const FitterOptions fopt_;
  ReportOptions report_;
  const bool show_progress_;
  const bool stream_;
  bool ok_ = true;
  bool first_file_ = true;          // the streamed JSON's first file is still to come
  Json live_files_ = Json::array();  // --live --json: the files' recorded FITs
};

}  // namespace

void setup_refit(CLI::App& app) {
  auto opt = std::make_shared<RefitCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "refit", "Refit LCM logs exactly as spindown-fitter did live (same runs, same numbers); --compare checks it");
  sub->footer(
      "Reads each log in its own order with its own timestamps (never file:// replay). Several logs are read as "
      "sessions in time order: a logger's rotated files are one session (a run across a file boundary is whole, as "
      "live); a log overlapping another in time is a session of its own. Runs are listed by bench, then run "
      "number; in JSON each run also has bench.id, first_seq and last_seq, and a session of several files "
      "session_files.\n"
      "J and K_b: the command line (--inertia…, --kb…), else the bench's --bench-config file ([bench]), else the "
      "log's CONFIG, else the lab's: what the first two name wins over the CONFIG and each run says so (J/K_b: …); "
      "without them a refit equals live. --bench-config's [motor]/[baseline]/[health] give each run a health "
      "verdict, as spindown-fitter --bench-config does live. --compare refits with the J and K_b the live fitter "
      "used (the CONFIG, else the flags as its defaults) and tells a verdict only one side has (the live fitter "
      "had a bench file, this refit none, or the other way) from a difference in the numbers.\n"
      "Exit codes: 0 ok, 1 a log or run could not be used or --compare found a difference, 2 bad usage.");
  sub->add_option("LOG", opt->logs, "LCM event log(s) (spindown-logger, lcm-logger); rotated files in any order")
      ->required();
  sub->add_flag("--json", opt->json, "Print one JSON object {\"files\":[{\"runs\":[…]}]} instead of tables");
  sub->add_option("--bench", opt->bench_regex, "Only benches whose id matches this regex (default all)");
  sub->add_option("--models", opt->models, "Models to fit: viscous,coulomb,combined (default all)")
      ->delimiter(',')
      ->allow_extra_args(false);
  sub->add_flag("--lab-units", opt->lab_units, "Also give the lab's units");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");
  sub->add_flag("--no-progress", opt->no_progress, "No progress line on a terminal (there is none when stderr is not one)");
  auto* live = sub->add_flag("--live", opt->live, "Print the FIT messages recorded in the log instead of refitting");
  sub->add_flag("--explain", opt->explain,
                "Also each run's EXPLAIN as the live fitter publishes it (the discrepancy workflow on the FIT's own "
                "window); in JSON the file's \"explains\"")
      ->excludes(live);
  sub->add_option("--explain-base", opt->explain_base,
                  "The EXPLAIN's starting model, as spindown-fitter --explain-base (default viscous)")
      ->capture_default_str();
  sub->add_flag("--compare", opt->compare,
                "Refit and compare with the recorded FIT messages, timing fields aside (exit 1 on a difference)")
      ->excludes(live);
  sub->add_option("--max-benches", opt->max_benches,
                  "Benches held at once, as the live spindown-fitter --max-benches (evictions are replayed too)")
      ->check(CLI::PositiveNumber);
  sub->add_option("--admit-rate", opt->admit_rate_hz, "New benches admitted per second, as spindown-fitter --admit-rate")
      ->check(CLI::PositiveNumber);
  sub->add_option("--silent", opt->silent_s,
                  "Seconds without samples (log time) that close a bench's open run, as spindown-fitter --silent")
      ->check(CLI::PositiveNumber);
  sub->add_option("--replay-window", opt->replay_window_s, "With --key: as spindown-fitter --replay-window")
      ->check(CLI::PositiveNumber);
  sub->add_option("--takeover", opt->takeover_s, "As spindown-fitter --takeover")->check(CLI::NonNegativeNumber);
  sub->add_flag("--ignore-config", opt->ignore_config,
                "Never use the log's CONFIG: J and K_b from the flags, the bench file, else the lab's")
      ->group("Bench");
  auto note_given = add_input_options(sub, opt->input, {.bench_config = true, .text = false});
  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_refit(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_refit(const RefitCommandOptions& o) { return RefitCommand(o).run(); }

}  // namespace spindown::cli
