// spindown-web: the lab in a browser. Listens (read-only) to every bench's SPINDOWN.<bench>.*
// channels and the services' heartbeats, and serves over HTTP a room page (every bench as a
// tile, for the projector) and a page per bench (the run as it arrives, its cut and stop, the
// three models' curves, residuals, the explain story, earlier runs, CSV, a print layout), pushed
// live with Server-Sent Events. SIGINT/SIGTERM end it with exit code 0. The logic is in core/web.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <memory>
#include <optional>

#include "service_command_line.hpp"
#include "spindown/bench_file.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/web_service.hpp"

namespace {

// The command line into o; an exit code when the program ends here (--help 0, bad usage 2).
std::optional<int> parse_options(int argc, char** argv, spindown::WebServiceOptions& o) {
  CLI::App app{"spindown-web: the lab in a browser (room page, bench pages, live over Server-Sent Events)"};
  std::string listen = "127.0.0.1:8080";
  std::vector<std::string> bench_configs;
  bool si_units = false;
  spindown::service::LabConnectionOptions connection;
  connection.add_to(app);
  app.add_option("--listen", listen,
                 "ADDR:PORT to serve on: 127.0.0.1:8080 (this PC only), 0.0.0.0:8080 (every network of this PC), "
                 "the lab LAN's address of this PC, [::]:8080")
      ->capture_default_str();
  auto* fd = app.add_option("--listen-fd", o.server.listen_fd,
                            "serve on this listening TCP socket, inherited from the caller (deploy/run-lab), "
                            "instead of --listen")
                  ->check(CLI::Range(3, 1 << 20));
  app.add_option("--allow-host", o.server.allow_hosts,
                 "a name the pages may be asked for beside IP addresses, localhost and this PC's name (repeat for "
                 "more): a lab that reaches the page as http://lab-pc.school.example:8080/ gives that name; any other "
                 "Host is refused (421), so a page elsewhere cannot read the lab's data through a student's browser");
  app.add_option("--bench-config", bench_configs,
                 "bench TOML file(s) or a directory of them (/etc/spindown/benches): those benches have a tile from "
                 "the start, silent until heard");
  app.add_option("--max-clients", o.fanout.max_clients, "pages connected at once; the next is refused (503)")
      ->capture_default_str()
      ->check(CLI::Range(1, 2000));
  app.add_option("--silent-after", o.lab.silent_after_s, "seconds without samples before a bench shows silent")
      ->capture_default_str()
      ->check(CLI::Range(0.5, 3600.0));
  app.add_option("--runs-kept", o.lab.runs_kept, "runs kept per bench (the current one included)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--max-run-samples", o.lab.max_run_samples,
                 "samples kept per run at full resolution (the CSV); the pages get at most 2000 points a run")
      ->capture_default_str()
      ->check(CLI::Range(100, 1000000));
  app.add_option("--max-benches", o.lab.max_benches, "benches shown at once (the least recently heard goes)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000));
  app.add_flag("--si-units", si_units, "coefficients' text in SI (N·m·s/rad, N·m) instead of the lab's g·cm² units");
  if (const auto exit_code = spindown::service::parse(app, argc, argv)) return exit_code;
  std::string why;
  if (fd->count() == 0 && !spindown::parse_listen_address(listen, o.server.host, o.server.port, &why))
    return spindown::service::bad_usage("spindown-web", "--listen: " + why);
  try {
    for (auto& [bench, file] : spindown::load_bench_files(bench_configs).files) o.lab.expected_benches.push_back(bench);
  } catch (const std::exception& e) {
    return spindown::service::bad_usage("spindown-web", fmt::format("--bench-config: {}", e.what()));
  }
  o.lab.lab_units = !si_units;
  if (!o.lab.is_valid(&why)) return spindown::service::bad_usage("spindown-web", why);
  // Only this lab's messages, and with the lab key only signed ones (docs/security.md): the
  // others are counted and named on the pages, never shown as real.
  const auto lab = connection.resolve(&why);
  if (!lab) return spindown::service::bad_usage("spindown-web", why);
  o.lcm_url = lab->lcm_url;
  o.lab.signatures_checked = lab->lab.key.has_value();
  o.lab.lab_name = lab->lab.lab;  // the gate below refuses what the key did not sign
  o.check = [g = std::make_shared<spindown::MessageGate>(lab->gate())](
                std::string_view channel, const void* data, std::int64_t size,
                std::int64_t recv_utime) -> std::optional<spindown::GateResult> {
    spindown::GateResult r = g->check(channel, data, size, recv_utime);
    if (r.refused()) return r;
    return std::nullopt;
  };
  fmt::print(stderr, "spindown-web: {}\n", spindown::lab_settings_text(lab->lab));
  return std::nullopt;
}

}  // namespace

int main(int argc, char** argv) {
  spindown::WebServiceOptions o;
  if (const auto exit_code = parse_options(argc, argv, o)) return *exit_code;
  spindown::StopSignals stop({.ignore_sigpipe = true});
  spindown::WebService service(o);
  std::string why;
  if (!service.start(&why)) {
    fmt::print(stderr, "spindown-web: {}\n", why);
    return 1;
  }
  fmt::print(stderr, "spindown-web: serving {} (lab on {}; at most {} pages)\n", service.url(),
             o.lcm_url.empty() ? "LCM's default URL" : o.lcm_url, o.fanout.max_clients);
  return service.run(stop);
}
