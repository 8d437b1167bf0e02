#include "explain_command.hpp"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <exception>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <span>
#include <string>

#include "exit_codes.hpp"
#include "file_problems.hpp"
#include "spindown/bench.hpp"
#include "spindown/explain.hpp"
#include "spindown/explain_report.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/offline_pipeline.hpp"
#include "spindown/read_recording.hpp"
#include "spindown/runs.hpp"

namespace spindown::cli {

namespace {

struct ExplainPlan {
  ReadOptions read;
  ExplainOptions explain;
  BenchChoice bench;             // the command line's J and K_b (choose_bench_params)
  BenchFiles bench_files;        // --bench-config, by bench id: [bench] J and K_b
  BenchNaming naming;            // --roster, --bench-pattern: a text file's bench
};

ExplainPlan plan_from(const ExplainCommandOptions& o) {
  ExplainPlan plan;
  plan.bench = bench_choice_from(o.input);
  plan.explain.bench = plan.bench.given;
  std::string why;
  plan.explain.base = parse_effect_list(o.base, &why);
  if (plan.explain.base.empty()) bad_usage(fmt::format("--base: {}", why));
  if (!plan.explain.is_valid(&why)) bad_usage(fmt::format("--base: {}", why));

  plan.read = read_options_from(o.input);
  plan.naming = naming_from(o.input);
  plan.bench_files = bench_files_from(o.input, std::cerr);
  return plan;
}

// Read, segment and explain one file (the offline path: offline_pipeline.hpp). Problems become
// diagnostics or failures, never exceptions.
FileExplain explain_file(const std::string& path, const ExplainPlan& plan) {
  struct Sink : OfflineSink {
    const ExplainPlan& plan;
    FileExplain out;
    explicit Sink(const ExplainPlan& p) : plan(p) {}
    void recording(const OfflineRecording& r) override { out.samples += r.recording.size(); }
    void diagnostics(const OfflineRecording&, From, std::span<const Diagnostic> diags) override {
      out.diagnostics.insert(out.diagnostics.end(), diags.begin(), diags.end());
    }
    void failure(const OfflineRecording*, std::string why) override { out.failures.push_back(std::move(why)); }
    void run(const OfflineRecording& r, const Run& run) override {
      ExplainOptions opt = plan.explain;
      opt.bench = r.params;
      ExplainResult result = explain_run(r.recording, run, opt);
      if (!result.ok) out.failures.push_back(r.where + fmt::format("run {}: {}", run.number, result.message));
      // An LCM log of several benches: each run says whose it is (run numbers restart per bench).
      // A text file named by the roster or --bench-pattern too.
      const bool lcm_log = r.info && r.info->format == FileFormat::lcm_log;
      if (r.count > 1 || (!lcm_log && !r.bench.empty())) out.run_bench.push_back(!r.bench.empty() ? r.bench : r.recording.source);
      out.runs.push_back(std::move(result));
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

void setup_explain(CLI::App& app) {
  auto opt = std::make_shared<ExplainCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "explain", "Find where the base model and the measurement disagree, name the missing effect, add it, repeat");
  sub->footer("Effects: viscous, coulomb, stribeck, windage, sensor_offset (combined = viscous,coulomb).\n"
              "Samples, zero level, weights and names are spindown fit's: the base model is fit's model of that name "
              "(c1 viscous, c2 Coulomb, c3/c4 combined, ω0).\n"
              "Exit codes: 0 ok, 1 a file or run could not be used (the others are still reported), 2 bad usage.");
  sub->add_option("FILE", opt->files, "Arduino/PuTTY log, delimited text (CSV/TSV) or LCM log")->required();
  sub->add_option("--base", opt->base,
                  "Starting model: viscous (the lab's belief, default), coulomb, combined, or EFFECT,EFFECT,…");
  sub->add_flag("--json", opt->json, "Print one JSON object {\"files\":[{\"runs\":[{\"steps\":…}]}]} instead of text");
  sub->add_option("--svg", opt->svg,
                  "Write a figure (measurement, the model after each step with its RMSE, residuals) to this file");
  sub->add_flag("--lab-units", opt->lab_units, "Also give the lab's units (g·cm², g·cm²·s⁻¹, g·cm²·rad·s⁻²), as fit does");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic, notes included");

  auto note_given = add_input_options(sub, opt->input);

  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_explain(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_explain(const ExplainCommandOptions& options) {
  const ExplainPlan plan = plan_from(options);
  ReportOptions report;
  report.lab_units = options.lab_units;
  std::vector<FileExplain> files;
  bool all_usable = true;
  for (const auto& path : options.files) {
    FileExplain file = explain_file(path, plan);
    report_file_problems(std::cerr, file.file, file.diagnostics, file.failures, options.verbose,
                         options.verbose ? 0 : 8);
    all_usable = all_usable && file.usable();
    if (!options.json) {
      std::cout << format_file_explain(file, report) << std::flush;
    }
    files.push_back(std::move(file));
  }
  // replace: bytes that are not UTF-8 (a Latin-1 file name) never abort the output.
  if (options.json)
    std::cout << explain_report_json(files, report).dump(2, ' ', false, Json::error_handler_t::replace) << std::endl;
  if (!options.svg.empty()) {
    std::ofstream svg(options.svg, std::ios::binary | std::ios::trunc);
    if (svg) svg << explain_svg(files);
    if (!svg || !svg.flush()) {
      std::cerr << fmt::format("{}: error: cannot write the figure: {}\n", options.svg, std::strerror(errno));
      return exit_unusable;
    }
  }
  return all_usable ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
