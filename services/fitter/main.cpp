// spindown-fitter: finds every bench's spin-down runs live and publishes their life on
// SPINDOWN.<bench>.RUN, the friction fits on SPINDOWN.<bench>.FIT and its own heartbeat on
// SPINDOWN.<instance>.STATUS. SIGINT/SIGTERM end it with exit code 0.
#include <CLI/CLI.hpp>
#include <cstdlib>
#include <fmt/format.h>
#include <optional>

#include "fitter_service.hpp"
#include "service_command_line.hpp"
#include "spindown/bench.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/effects.hpp"
#include "spindown/fit.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/session_id.hpp"
#include "spindown/stop_signal.hpp"

namespace {

// The command line into o; an exit code when the program ends here (--help 0, bad usage 2).
std::optional<int> parse_options(int argc, char** argv, spindown::FitterServiceOptions& o) {
  CLI::App app{"spindown-fitter: SPINDOWN.<bench>.SAMPLE|CONFIG -> RUN, FIT and STATUS, live"};
  std::vector<std::string> models;
  double kv = 0;
  std::vector<std::string> bench_configs;
  spindown::service::LabConnectionOptions connection;
  connection.add_to(app);
  app.add_option("--replay-window", o.core.gate.replay_window_s,
                 "with --key: a signed message sent more than this many seconds from its receive time is refused "
                 "(a replay, or a clock that is off)")
      ->check(CLI::PositiveNumber);
  app.add_option("--takeover", o.core.stream.takeover_s,
                 "seconds a bench's source must be quiet before another source on its channel (a restarted bridge) "
                 "starts a new stream; while both send, the second is named and refused")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--bench", o.core.bench_regex, "benches to fit: regex on the bench id (default all)");
  app.add_option("--instance", o.instance, "instance name: heartbeat on SPINDOWN.<instance>.STATUS")
      ->check([](const std::string& s) {
        std::string why;
        return spindown::is_valid_bench_id(s, &why) ? std::string() : why;
      });
  auto* j = app.add_option("--inertia", o.core.default_bench.inertia_kg_m2,
                           "J (kg·m²) for benches without CONFIG (default: the lab's)")
                ->check(CLI::PositiveNumber);
  auto* kb = app.add_option("--kb", o.core.default_bench.kb_v_s_per_rad,
                            "K_b (V·s/rad) for benches without CONFIG (default: the lab's)")
                 ->check(CLI::PositiveNumber);
  auto* kvo = app.add_option("--speed-constant", kv, "K_b from a speed constant (rpm/V), instead of --kb")
                  ->check(CLI::PositiveNumber)
                  ->excludes(kb);
  app.add_flag("--ignore-config", o.core.ignore_config, "always use --inertia/--kb, never a bench's CONFIG");
  app.add_option("--models", models, "models: viscous,coulomb,combined (default all)")->delimiter(',');
  app.add_option("--max-benches", o.core.max_benches,
                 "benches held at once; a new one takes the place of the least recently active bench with no run in "
                 "progress, or is refused");
  app.add_option("--admit-rate", o.core.admit_rate_hz,
                 "new benches admitted per second past the first --max-benches (a flood of bench ids is refused)")
      ->check(CLI::PositiveNumber);
  app.add_option("--silent", o.core.silent_s,
                 "seconds without samples that close a bench's open run (fitted to its last sample; what resumes "
                 "of that coast is partial, never given a cut); judged only when nothing received still waits, so "
                 "a fitter that was stopped or starved first handles its backlog")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-rate", o.core.max_rate_hz, "samples/s per bench before messages are dropped (0: no cap)");
  app.add_option("--max-coast", o.core.runs.max_coast_s, "seconds before a coast that never stops is closed");
  app.add_option("--max-buffer", o.core.runs.max_buffer, "samples buffered per bench at most");
  app.add_option("--status-period", o.status_period_s, "seconds between heartbeats")->check(CLI::Range(0.05, 60.0));
  std::string explain_base = "viscous";
  app.add_option("--explain-base", explain_base,
                 "base model of the discrepancy workflow published on SPINDOWN.<bench>.EXPLAIN: "
                 "viscous|coulomb|combined|EFFECT,EFFECT… (default: viscous, the lab's belief)");
  bool no_explain = false;
  app.add_flag("--no-explain", no_explain, "do not run the discrepancy workflow (no EXPLAIN messages)");
  app.add_option("--bench-config", bench_configs,
                 "per-bench TOML file(s) or a directory of them (/etc/spindown/benches): [motor], [baseline], "
                 "[health] give each fit of that bench a motor health verdict");
  app.add_flag("-v,--verbose", o.verbose, "one line per run event and fit on stderr");
  if (const auto exit_code = spindown::service::parse(app, argc, argv)) return exit_code;

  if (j->count()) o.core.default_bench.inertia_source = "--inertia";
  if (kb->count()) o.core.default_bench.kb_source = "--kb";
  if (kvo->count()) {
    o.core.default_bench.kb_v_s_per_rad = spindown::kb_from_speed_constant(kv);
    o.core.default_bench.kb_source = fmt::format("--speed-constant {} rpm/V", kv);
  }
  if (!models.empty()) {
    o.core.models.clear();
    for (const auto& name : models) {
      const auto kind = spindown::parse_model(name);
      if (!kind) {
        return spindown::service::bad_usage(
            "spindown-fitter", fmt::format("--models: unknown model '{}' (viscous, coulomb, combined)", name));
      }
      o.core.models.push_back(*kind);
    }
  }
  std::string why;
  try {
    for (auto& [bench, file] : spindown::load_bench_files(bench_configs).files) {
      for (const auto& w : file.warnings) fmt::print(stderr, "spindown-fitter: {}\n", w);
      o.core.health.emplace(bench, file.health);
    }
  } catch (const std::exception& e) {
    return spindown::service::bad_usage("spindown-fitter", fmt::format("--bench-config: {}", e.what()));
  }
  if (no_explain) {
    o.core.explain_base.clear();
  } else {
    o.core.explain_base = spindown::parse_effect_list(explain_base, &why);
    if (o.core.explain_base.empty()) return spindown::service::bad_usage("spindown-fitter", "--explain-base: " + why);
  }
  const auto lab = connection.resolve(&why);
  if (!lab) return spindown::service::bad_usage("spindown-fitter", why);
  o.lab = lab->lab;
  o.lcm_url = lab->lcm_url;
  const double replay_window_s = o.core.gate.replay_window_s;  // --replay-window
  o.core.gate = lab->gate();
  o.core.gate.replay_window_s = replay_window_s;
  if (!o.core.is_valid(&why)) return spindown::service::bad_usage("spindown-fitter", why);

  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  spindown::FitterServiceOptions o;
  if (const auto exit_code = parse_options(argc, argv, o)) return *exit_code;

  spindown::FitterService service(o);
  if (!service.good()) {
    fmt::print(stderr, "spindown-fitter: cannot start LCM{}{}\n", o.lcm_url.empty() ? "" : " at ", o.lcm_url);
    return 1;
  }
  spindown::StopSignals stop;
  fmt::print(stderr, "spindown-fitter: fitting benches matching '{}'{}; heartbeat on SPINDOWN.{}.STATUS; {}; session {}\n",
             o.core.bench_regex, o.lcm_url.empty() ? "" : " on " + o.lcm_url, o.instance,
             spindown::lab_settings_text(o.lab), spindown::session_text(service.session()));
  if (o.lab.key && !o.lab.key->warning.empty()) fmt::print(stderr, "spindown-fitter: warning: {}\n", o.lab.key->warning);
  if (!o.core.health.empty()) {
    std::string benches;
    for (const auto& [bench, cfg] : o.core.health) benches += (benches.empty() ? "" : ", ") + bench;
    fmt::print(stderr, "spindown-fitter: motor health verdicts for {}\n", benches);
  }
  return service.run(stop);
}
