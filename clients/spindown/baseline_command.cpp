#include "baseline_command.hpp"

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <span>
#include <sstream>

#include "exit_codes.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/fit.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/health_baseline.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/offline_pipeline.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/recording_time.hpp"
#include "spindown/runs.hpp"

namespace spindown::cli {

namespace {

std::string today_utc() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  return fmt::format("{:04}-{:02}-{:02}", utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday);
}

// Writes text to path through a temporary file in the same directory, so a reader never sees
// half a file. false and *why on failure.
bool write_file(const std::string& path, const std::string& text, std::string* why) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      *why = fmt::format("cannot write {}", tmp);
      return false;
    }
    out << text;
    out.flush();
    if (!out) {
      *why = fmt::format("cannot write {}", tmp);
      return false;
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    *why = fmt::format("cannot replace {}: {}", path, ec.message());
    std::filesystem::remove(tmp, ec);
    return false;
  }
  return true;
}

std::optional<std::string> read_text(const std::string& path, std::string* why) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    *why = fmt::format("cannot read {}", path);
    return std::nullopt;
  }
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The bench file text of a new file: the bench's id and its [baseline] section.
std::string new_bench_file(const std::string& bench, const std::string& section) {
  return fmt::format("bench_id = \"{}\"\n\n{}", bench, section);
}

// The command line's checks that need no file read: a valid bench id, no -o over a file.
void check_usage(const BaselineCommandOptions& o) {
  std::string why;
  if (!is_valid_bench_id(o.bench, &why)) bad_usage(fmt::format("--bench: {}", why));
  if (!o.output.empty() && std::filesystem::exists(o.output))
    bad_usage(fmt::format("-o {}: the file exists; use --update {} to replace its [baseline]", o.output, o.output));
}

// --update's bench file, its warnings on stderr (none without --update; bad usage when unreadable).
std::optional<BenchFile> load_update_file(const BaselineCommandOptions& o) {
  if (o.update.empty()) return std::nullopt;
  std::optional<BenchFile> file;
  try {
    file = load_bench_file(o.update);
    print_bench_file_warnings(*file, std::cerr);
    if (file->bench != o.bench)
      std::cerr << fmt::format("{}: warning: the file describes bench '{}', the baseline is for --bench {}\n",
                               o.update, file->bench, o.bench);
  } catch (const std::exception& e) {
    bad_usage(fmt::format("--update: {}", e.what()));
  }
  return file;
}

// Each run of the bench as read: what the baseline can be made of, and what not.
struct Seen {
  std::string source;
  std::optional<BaselineRun> run;  // a whole coast with a combined fit
  std::string why;                 // else why not
  std::optional<RecordedAt> at;    // when its cut was, as the file tells
};

// The offline path's sink for the bench's recordings: each run fitted (combined model) and kept
// as Seen; the reader's errors and the CONFIG's problems on stderr.
struct BaselineSink : OfflineSink {
  const FitOptions& fit_opt;
  std::vector<Seen> seen;
  bool all_read = true, bench_found = false;
  std::optional<RecordedAt> start;  // the current file's
  std::string current;              // the current file
  explicit BaselineSink(const FitOptions& f) : fit_opt(f) {}
  void recording(const OfflineRecording&) override { bench_found = true; }
  void diagnostics(const OfflineRecording&, From from, std::span<const Diagnostic> diags) override {
    // The reader's errors and the CONFIG's problems.
    for (const auto& d : diags)
      if (from == From::config || (from == From::reader && d.severity == Diagnostic::Severity::error))
        std::cerr << d.to_string() << '\n';
  }
  void failure(const OfflineRecording* r, std::string why) override {
    if (!r || r->recording.empty()) {
      all_read = false;  // the reader's error is already on stderr
      if (!r) std::cerr << fmt::format("{}: error: {}\n", current, why);
      return;
    }
    std::cerr << fmt::format("{}: {}\n", r->path, why);
  }
  void run(const OfflineRecording& r, const Run& run) override {
    FitOptions this_fit = fit_opt;
    this_fit.bench = r.params;
    const RunFit fit = fit_run(r.recording, run, this_fit);
    Seen s{fmt::format("{} run {}", r.path, run.number), std::nullopt, {}, std::nullopt};
    s.run = baseline_run(fit, s.source, &s.why);
    if (start && !r.recording.t_s.empty())
      s.at = RecordedAt{start->unix_s + (run.t_cut_s - r.recording.t_s.front()), start->local};
    seen.push_back(std::move(s));
  }
};

// The offline path (offline_pipeline.hpp) over the files, for this bench's recordings only.
void read_bench_runs(const BaselineCommandOptions& o, const BenchChoice& choice,
                     const std::optional<BenchFile>& update_file, BaselineSink& sink) {
  OfflinePlan plan{read_options_from(o.input), choice, {}, {}, {}};
  const BenchNaming naming = naming_from(o.input);
  plan.naming = &naming;
  plan.bench_file = [&update_file](const OfflineRecording&) { return update_file ? &*update_file : nullptr; };
  plan.wanted = [&o](const OfflineRecording& r) { return r.bench.empty() || r.bench == o.bench; };
  for (const auto& path : o.files) {
    // A class's files: those the roster or --bench-pattern gives to another bench are not this one's.
    if (naming.active()) {
      const BenchName name = naming.name(path, file_stem(path));
      if (name.bench != o.bench) {
        std::cout << fmt::format("  {:<8} {}: bench {} ({})\n", "skipped", path, name.bench,
                                 name.problem.empty() ? name.from : name.problem);
        continue;
      }
    }
    sink.bench_found = false;
    sink.current = path;
    sink.start = recording_start(path, FileFormat::automatic, plan.read);
    walk_file(path, plan, sink);
    if (!sink.bench_found) {
      std::cerr << fmt::format("{}: error: no samples of bench '{}' in this file\n", path, o.bench);
      sink.all_read = false;
    }
  }
}

// When the runs the baseline uses were recorded, the first and the last (as their files tell).
struct UsedSpan {
  std::optional<RecordedAt> first, last;
};

// Every run once, in the order read: what the baseline is made of, and what not.
UsedSpan list_runs(const std::vector<Seen>& seen, const std::vector<SetAsideRun>& set_aside, bool made) {
  const auto set_aside_why = [&set_aside](const std::string& source) -> const std::string* {
    for (const auto& r : set_aside)
      if (r.source == source) return &r.why;
    return nullptr;
  };
  UsedSpan used;
  for (const auto& s : seen) {
    if (!s.run) {
      std::cout << fmt::format("  {:<8} {}: {}\n", "not used", s.source, s.why);
    } else if (const std::string* aside = set_aside_why(s.source)) {
      std::cout << fmt::format("  set aside {}: {}\n", s.source, *aside);
    } else {
      std::cout << fmt::format("  {:<8} {}: c3 = {} N·m·s/rad, c4 = {} N·m\n", made ? "used" : "candidate", s.source,
                               format_value_error(s.run->c_viscous, s.run->c_viscous_stderr),
                               format_value_error(s.run->c_coulomb, s.run->c_coulomb_stderr));
      if (s.at) {
        if (!used.first || s.at->unix_s < used.first->unix_s) used.first = s.at;
        if (!used.last || s.at->unix_s > used.last->unix_s) used.last = s.at;
      }
    }
  }
  return used;
}

// Dated by the recordings (the last run used, as its file tells it), never by the day this runs;
// today only when no file tells.
void date_baseline(HealthBaseline& baseline, const UsedSpan& used) {
  if (used.last) {
    baseline.date = recorded_date_text(*used.last);
    if (recorded_date_text(*used.first) != baseline.date)
      std::cout << fmt::format("  the runs used were recorded {} to {}: the baseline is dated by the last\n",
                               recorded_date_text(*used.first), baseline.date);
  } else {
    baseline.date = today_utc();
    std::cerr << fmt::format("spindown baseline: warning: no recording date in these files (no PuTTY header, not an "
                             "LCM log): the baseline is dated today, {}; give the recordings' date with --date\n",
                             baseline.date);
  }
}

// The baseline where the command line says: --update's file (or a new file beside it when its
// [baseline] cannot be replaced cleanly), -o's new file, else stdout. False when a file could not
// be written (why on stderr).
bool write_baseline(const BaselineCommandOptions& o, const HealthBaseline& baseline) {
  const std::string section = baseline_toml_section(baseline);
  std::string why;
  if (!o.update.empty()) {
    const auto text = read_text(o.update, &why);
    std::optional<std::string> updated;
    if (text) updated = with_baseline_section(*text, baseline, &why);
    if (updated) {
      if (!write_file(o.update, *updated, &why)) {
        std::cerr << "spindown baseline: error: " << why << '\n';
        return false;
      }
      std::cout << fmt::format("[baseline] of {} updated in place (other keys and comments kept)\n", o.update);
      return true;
    }
    // Not cleanly replaceable: the original stays untouched, the section goes beside it.
    const std::string beside = o.update + ".baseline.toml";
    std::string werr;
    if (!write_file(beside, new_bench_file(o.bench, section), &werr)) {
      std::cerr << "spindown baseline: error: " << werr << '\n';
      return false;
    }
    std::cerr << fmt::format(
        "spindown baseline: warning: {} not changed ({}); the baseline is in a new file {}: copy its "
        "[baseline] section into the bench file\n",
        o.update, why, beside);
    return true;
  }
  if (!o.output.empty()) {
    if (!write_file(o.output, new_bench_file(o.bench, section), &why)) {
      std::cerr << "spindown baseline: error: " << why << '\n';
      return false;
    }
    std::cout << fmt::format("baseline written to {} (a new bench file with bench_id and [baseline])\n", o.output);
    return true;
  }
  std::cout << '\n' << section;
  return true;
}

}  // namespace

void setup_baseline(CLI::App& app) {
  auto opt = std::make_shared<BaselineCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "baseline", "Make a motor's health baseline from good runs (combined fits that converged) of one bench");
  sub->footer(
      "Writes the [baseline] section of the bench's TOML file: --update replaces it in place (other keys and "
      "comments kept; [bench] J/K_b of that file used for the fits), -o writes a new file, neither prints it.\n"
      "Exit codes: 0 ok, 1 no good run or the file could not be written, 2 bad usage.");
  sub->add_option("FILE", opt->files, "LCM log, Arduino/PuTTY log or delimited text with the bench's good runs")
      ->required();
  sub->add_option("--bench", opt->bench, "Bench id: the bench in an LCM log; names the bench in the file")
      ->required();
  auto* out = sub->add_option("-o,--output", opt->output, "Write a new bench file (refused if it exists)");
  sub->add_option("--update", opt->update, "Replace [baseline] in this existing bench file")
      ->check(CLI::ExistingFile)
      ->excludes(out);
  sub->add_option("--date", opt->date,
                  "Date recorded in the baseline (default: the recordings' date, from a PuTTY header or an LCM "
                  "log's times: the last run used; today only when no file tells)");
  auto note_given = add_input_options(sub, opt->input, {.bench_config = false, .text = true});
  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_baseline(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_baseline(const BaselineCommandOptions& o) {
  check_usage(o);
  // J and K_b by the one rule (choose_bench_params): flags, else the bench file being updated,
  // else an LCM log's CONFIG, else the lab's.
  const BenchChoice choice = bench_choice_from(o.input);
  FitOptions fit_opt;
  fit_opt.models = {ModelKind::combined};
  fit_opt.bench = choice.given;
  const std::optional<BenchFile> update_file = load_update_file(o);
  // Each run is listed once the baseline is made: used, set aside (and why) or not used (and why).
  BaselineSink sink(fit_opt);
  read_bench_runs(o, choice, update_file, sink);
  std::vector<BaselineRun> good;
  for (const auto& s : sink.seen)
    if (s.run) good.push_back(*s.run);
  const std::size_t runs_seen = sink.seen.size();

  std::string source = fmt::format("bench {}:", o.bench);
  for (const auto& f : o.files) source += " " + std::filesystem::path(f).filename().string();
  std::string why;
  std::vector<SetAsideRun> set_aside;
  auto baseline = make_baseline(good, o.date, source, &why, &set_aside);
  const UsedSpan used = list_runs(sink.seen, set_aside, baseline.has_value());
  if (!baseline) {
    std::cerr << fmt::format("spindown baseline: error: {} ({} run{} seen)\n", why, runs_seen,
                             runs_seen == 1 ? "" : "s");
    return exit_unusable;
  }
  if (o.date.empty()) date_baseline(*baseline, used);
  std::cout << fmt::format(
      "baseline of bench {} from {} of {} run{} (recorded {}): c3 = {} N·m·s/rad (spread {:.2g}), c4 = {} N·m "
      "(spread {:.2g}), J = {:.6g} kg·m²\n",
      o.bench, baseline->runs, runs_seen, runs_seen == 1 ? "" : "s", baseline->date,
      format_value_error(baseline->c_viscous, baseline->c_viscous_stderr), baseline->c_viscous_spread,
      format_value_error(baseline->c_coulomb, baseline->c_coulomb_stderr), baseline->c_coulomb_spread,
      baseline->inertia_kg_m2);
  if (!write_baseline(o, *baseline)) return exit_unusable;
  return sink.all_read ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
