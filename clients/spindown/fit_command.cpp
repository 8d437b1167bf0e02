#include "fit_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <cstdio>
#include <exception>
#include <fmt/format.h>
#include <iostream>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "csv_output.hpp"
#include "exit_codes.hpp"
#include "file_problems.hpp"
#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/fit.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/motor_health.hpp"
#include "spindown/offline_pipeline.hpp"
#include "spindown/ordered_parallel.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/run_table.hpp"
#include "spindown/runs.hpp"

namespace spindown::cli {

namespace {

// Everything the options say, checked once before any file is read (bad usage: exit 2).
struct FitPlan {
  ReadOptions read;
  FitOptions fit;
  BenchChoice bench;             // the command line's J and K_b (choose_bench_params)
  ReportOptions report;
  BenchFiles bench_files;        // --bench-config, by bench id
  BenchNaming naming;            // --roster, --bench-pattern: a text file's bench
};

FitPlan plan_from(const FitCommandOptions& o) {
  FitPlan plan;
  plan.bench = bench_choice_from(o.input);
  plan.fit.bench = plan.bench.given;
  plan.naming = naming_from(o.input);
  std::string why;
  if (!o.models.empty()) plan.fit.models = models_from(o.models);
  if (!plan.fit.is_valid(&why)) bad_usage(why);

  plan.read = read_options_from(o.input);
  plan.bench_files = bench_files_from(o.input, std::cerr);

  plan.report.lab_units = o.lab_units;
  plan.report.details = o.details;
  plan.report.max_diagnostics = o.verbose ? 0 : 8;
  plan.report.diagnostics_in_text = false;  // they go to stderr, with the failures
  return plan;
}

// Read, segment and fit one file (the offline path: offline_pipeline.hpp). Problems become
// diagnostics or failures, never exceptions.
FileFit fit_file(const std::string& path, const FitPlan& plan) {
  struct Sink : OfflineSink {
    const FitPlan& plan;
    FileFit out;
    explicit Sink(const FitPlan& p) : plan(p) {}
    void file_read(std::span<const Recording>, std::span<const RecordingInfo> info, std::size_t) override {
      out.lcm_log = !info.empty() && info.front().format == FileFormat::lcm_log;
    }
    void recording(const OfflineRecording& r) override {
      if (!out.lcm_log) {
        out.bench = r.bench;
        out.student = r.student;
      }
      out.samples += r.recording.size();
      out.lines_read += r.recording.lines_read;
      out.lines_skipped += r.recording.lines_skipped;
    }
    void diagnostics(const OfflineRecording&, From, std::span<const Diagnostic> diags) override {
      out.diagnostics.insert(out.diagnostics.end(), diags.begin(), diags.end());
    }
    void failure(const OfflineRecording*, std::string why) override { out.failures.push_back(std::move(why)); }
    void bench_chosen(const OfflineRecording& r) override {
      if (!r.bench_file && !plan.bench_files.files.empty())
        out.diagnostics.push_back({Diagnostic::Severity::warning, r.recording.source, 0,
                                   fmt::format("no --bench-config file for bench '{}': no health verdict", r.bench)});
    }
    void run(const OfflineRecording& r, const Run& run) override {
      FitOptions fit_opt = plan.fit;
      fit_opt.bench = r.params;
      RunFit fit = fit_run(r.recording, run, fit_opt);
      // An LCM log of several benches: each run says whose it is (run numbers restart per bench).
      if (r.count > 1) out.run_bench.push_back(!r.bench.empty() ? r.bench : r.recording.source);
      // A text file named by the roster or --bench-pattern: its runs carry that bench id too.
      else if (!out.lcm_log && !r.bench.empty()) out.run_bench.push_back(r.bench);
      out.run_student.resize(out.runs.size());
      out.run_student.push_back(r.recording.name_before(run.cut_index));
      if (fit.best.empty()) {
        std::string why;
        for (const auto& m : fit.models)
          if (!m.message.empty()) why += fmt::format("; {}: {}", model_name(m.kind), m.message);
        out.failures.push_back(r.where + fmt::format("run {}: no model converged{}", run.number, why));
      }
      if (r.bench_file) {
        out.health.resize(out.runs.size());
        out.health.push_back(assess_health(fit, r.bench_file->health));
      }
      out.runs.push_back(std::move(fit));
    }
  } sink(plan);
  sink.out.file = path;
  OfflinePlan offline{plan.read, plan.bench, {}, {}, {}};
  offline.naming = &plan.naming;
  offline.bench_file = [&plan](const OfflineRecording& r) { return plan.bench_files.for_bench(r.bench); };
  walk_file(path, offline, sink);
  return std::move(sink.out);
}

}  // namespace

void setup_fit(CLI::App& app) {
  auto opt = std::make_shared<FitCommandOptions>();
  CLI::App* sub = app.add_subcommand("fit", "Fit viscous, Coulomb and combined friction to each spin-down run");
  sub->footer("Exit codes: 0 ok, 1 a file or run could not be used (the others are still reported), 2 bad usage.");
  sub->add_option("FILE", opt->files, "Arduino/PuTTY log, delimited text (CSV/TSV) or LCM log")->required();
  auto* json = sub->add_flag("--json", opt->json,
                             "Print one JSON object {\"files\":[{\"runs\":[{\"models\":…}]}]} instead of tables");
  sub->add_flag("--pretty", opt->pretty,
                "Indent the JSON (as on a terminal); into a pipe or a file it is compact, without layout whitespace")
      ->needs(json);
  sub->add_option("--table", opt->table,
                  "A class's table instead: one row per run across all files (file, bench, student, best model, "
                  "c1…c4 ± errors, doubts, health), as csv or json (an array of the same rows)")
      ->check(CLI::IsMember({"csv", "json"}))
      ->excludes(json);
  sub->add_option("-o,--output", opt->output,
                  "Write the output (the tables, --json or --table) to this file instead of stdout; a --table csv "
                  "file starts with a UTF-8 byte-order mark, so that Excel shows names and units right");
  add_csv_locale_option(sub, opt->csv_locale);
  sub->add_option("--models", opt->models, "Models to fit, comma-separated: viscous,coulomb,combined (default all)")
      ->delimiter(',')
      ->allow_extra_args(false);  // one value per flag: `--models combined a.tsv b.tsv` leaves the files alone
  sub->add_flag("--lab-units", opt->lab_units, "Also give the lab's units (g·cm², g·cm²·s⁻¹, g·cm²·rad·s⁻²)");
  sub->add_flag("--details", opt->details,
                "Also give each model's 95 % intervals, parameter correlations and reduced χ² (JSON always has them)");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");

  sub->add_option("-j,--jobs", opt->jobs, "Files fitted at once (default 0: one per core); output keeps the order given")
      ->check(CLI::Range(0u, 1024u));
  auto note_given = add_input_options(sub, opt->input);

  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_fit(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_fit(const FitCommandOptions& options) {
  const FitPlan plan = plan_from(options);
  const bool to_file = !options.output.empty() && options.output != "-";
  const CsvStyle csv_style = csv_style_from(options.csv_locale, to_file);  // the table in a file: the mark
  if (!options.csv_locale.empty() && options.table != "csv") bad_usage("--csv-locale needs --table csv");
  std::ofstream file;
  if (to_file) {
    file.open(options.output, std::ios::binary | std::ios::trunc);
    if (!file) {
      std::cerr << fmt::format("spindown fit: cannot write {}: {}\n", options.output, std::strerror(errno));
      return exit_unusable;
    }
  }
  std::ostream& out = to_file ? static_cast<std::ostream&>(file) : std::cout;
  bool all_usable = true;
  // --json: one document, assembled from each file's text as it comes. On a terminal it is
  // printed once every file is done, so that stderr's problems never land inside it; into a
  // file or a pipe it goes out in pieces as the workers finish them, so that writing it overlaps
  // the fitting instead of following it (5 MB for 1000 runs: milliseconds, and a 5 MB buffer
  // grown by doubling).
  // Compact (no layout whitespace) unless it is for a person: a terminal, or --pretty.
  const bool json_in_pieces = options.json && (to_file || !isatty(STDOUT_FILENO));
  const bool json_compact = json_in_pieces && !options.pretty;
  std::string json;
  FitReportJsonText json_files(json_compact);
  constexpr std::size_t json_piece_bytes = 256 * 1024;
  // --table: one row per run across the files, in the order given.
  const bool csv_table = options.table == "csv", json_table = options.table == "json";
  bool first_row = true;
  if (csv_table) out << run_table_csv_header(csv_style);
  if (json_table) out << '[';
  struct Done {
    FileFit file;
    std::string text;  // the file's tables, JSON entry or table rows, formatted by the worker too
  };
  // Files are independent: fit them on every core, report them in the order given.
  for_each_ordered(
      options.files.size(), options.jobs == 0 ? default_jobs() : options.jobs,
      [&](std::size_t i) {
        Done d{fit_file(options.files[i], plan), {}};
        // Bytes that are not UTF-8 (a Latin-1 file name or config string) are replaced, never abort the output.
        if (csv_table)
          d.text = run_table_csv_rows(d.file, csv_style);
        else if (!json_table)
          d.text = options.json ? file_fit_json_text(d.file, plan.report, json_compact) : format_file_fit(d.file, plan.report);
        return d;
      },
      [&](std::size_t, Done d) {
        report_file_problems(std::cerr, d.file.file, d.file.diagnostics, d.file.failures, options.verbose,
                             plan.report.max_diagnostics);
        all_usable = all_usable && d.file.usable();
        if (json_table) {
          std::string rows;
          append_run_table_json_rows(d.file, rows, first_row);
          out << rows;
        } else if (options.json) {
          json_files.add(d.text, json);
          if (json_in_pieces && json.size() >= json_piece_bytes) {
            out << json;
            json.clear();
          }
        } else {
          out << d.text << (csv_table ? "" : "\n");
          out.flush();
        }
      });
  if (json_table) out << (first_row ? "]" : "\n]") << std::endl;
  if (options.json) {
    json_files.finish(json);
    out << json << std::endl;
  }
  if (to_file) {
    file.close();
    if (!file) {
      std::cerr << fmt::format("spindown fit: writing {} failed\n", options.output);
      return exit_unusable;
    }
  }
  return all_usable ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
