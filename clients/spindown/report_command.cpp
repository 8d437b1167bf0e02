#include "report_command.hpp"

#include <CLI/CLI.hpp>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <unistd.h>

#include "exit_codes.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/html_report.hpp"
#include "spindown/progress.hpp"
#include "spindown/build_session_report.hpp"

namespace spindown::cli {

namespace {

SessionReportOptions plan_from(const ReportCommandOptions& o) {
  SessionReportOptions plan;
  plan.bench = bench_choice_from(o.input);
  plan.fit.bench = plan.bench.given;
  plan.read = read_options_from(o.input);
  std::string why;
  if (!o.models.empty()) plan.fit.models = models_from(o.models);
  if (!plan.fit.is_valid(&why)) bad_usage(why);
  plan.explain_runs = !o.no_explain;
  plan.explain.base = parse_effect_list(o.base, &why);
  if (plan.explain.base.empty()) bad_usage(fmt::format("--base: {}", why));
  if (!plan.explain.is_valid(&why)) bad_usage(fmt::format("--base: {}", why));
  plan.naming = naming_from(o.input, o.text_bench);
  // One loader for fit, report and the fitter: files or directories, duplicate benches refused.
  for (const auto& [bench, file] : bench_files_from(o.input, std::cerr).files)
    plan.references.emplace(bench, bench_reference(file));
  return plan;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

}  // namespace

void setup_report(CLI::App& app) {
  auto opt = std::make_shared<ReportCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "report", "Write one self-contained HTML page for a session: fits, residuals, explain story, health, drift");
  sub->footer("Text files belong to the bench the --roster or --bench-pattern names, else --bench, else their "
              "file name; LCM logs name their benches. A --bench-config file (the bench's TOML: bench_id, [bench], [motor], [baseline], [health]) "
              "gives that bench's health verdicts a datasheet or baseline; without one the page says "
              "\"no reference configured\".\n"
              "Exit codes: 0 ok, 1 a file or run could not be used (the page is still written), 2 bad usage.");
  sub->add_option("FILE", opt->files, "Arduino/PuTTY log, delimited text (CSV/TSV) or LCM log")->required();
  sub->add_option("-o,--output", opt->output, "The HTML page to write")->required();
  sub->add_option("--bench", opt->text_bench, "Bench id for the text files (default: each file's name)");
  sub->add_option("--base", opt->base, "The explain workflow's starting model (default viscous)");
  sub->add_option("--models", opt->models, "Models to fit: viscous,coulomb,combined (default all)")
      ->delimiter(',')
      ->allow_extra_args(false);
  sub->add_flag("--no-explain", opt->no_explain, "Leave out the explain story (faster)");
  sub->add_option("--title", opt->title, "Page title");
  sub->add_flag("--no-progress", opt->no_progress, "No progress line on a terminal");
  sub->add_flag("-v,--verbose", opt->verbose, "Show every diagnostic on stderr, notes included");
  auto note_given = add_input_options(sub, opt->input);
  sub->callback([opt, note_given]() {
    note_given();
    const int code = run_report(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_report(const ReportCommandOptions& o) {
  const SessionReportOptions plan = plan_from(o);
  SessionReport report;
  {
    ProgressReporter progress(STDERR_FILENO, !o.no_progress && ProgressReporter::is_terminal(STDERR_FILENO));
    report = build_session_report(o.files, plan, [&](const ReportProgress& p) {
      // Numbers first, the file name last: a narrow terminal cuts the name, not the ETA.
      progress.update(static_cast<std::int64_t>(p.bytes_done), static_cast<std::int64_t>(p.bytes_total), "report",
                      fmt::format("runs {}/{}  {}", p.runs_done, p.runs_found,
                                  std::filesystem::path(p.file).filename().string()));
    });
  }  // the progress line is gone before anything else goes to stderr
  for (const auto& file : report.files) {
    std::vector<Diagnostic> shown;
    for (const auto& d : file.diagnostics)
      if (o.verbose || d.severity != Diagnostic::Severity::note) shown.push_back(d);
    for (const auto& line : summarize_diagnostics(shown, o.verbose ? 0 : 8)) std::cerr << line << '\n';
    for (const auto& why : file.failures) std::cerr << file.file << ": error: not used: " << why << '\n';
  }
  for (const auto& note : report.notes) std::cerr << "spindown report: note: " << note << '\n';

  HtmlReportOptions html;
  html.title = o.title;
  html.generated = utc_now();
  {
    std::ofstream out(o.output, std::ios::binary | std::ios::trunc);
    if (out) out << render_html_report(report, html);
    if (!out || !out.flush()) {
      std::cerr << o.output << ": error: cannot write the report\n";
      return exit_unusable;
    }
  }
  std::size_t drifting = 0;
  for (const auto& b : report.benches) drifting += b.viscous.drifting || b.coulomb.drifting;
  std::cout << fmt::format("{}: {} run{} on {} bench{} from {} file{}; {} bench{} drifting\n", o.output,
                           report.runs.size(), report.runs.size() == 1 ? "" : "s", report.benches.size(),
                           report.benches.size() == 1 ? "" : "es", report.files.size(),
                           report.files.size() == 1 ? "" : "s", drifting, drifting == 1 ? "" : "es");
  return report.usable() ? exit_ok : exit_unusable;
}

}  // namespace spindown::cli
