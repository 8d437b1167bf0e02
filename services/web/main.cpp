// spindown-web: the lab in a browser. Listens (read-only) to every bench's SPINDOWN.<bench>.*
// channels and the services' heartbeats, and serves over HTTP a room page (every bench as a
// tile, for the projector) and a page per bench (the run as it arrives, its cut and stop, the
// three models' curves, residuals, the explain story, earlier runs, CSV, a print layout), pushed
// live with Server-Sent Events. SIGINT/SIGTERM end it with exit code 0. The logic is in core/web.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <memory>
#include <optional>

#include "spindown/bench_file.hpp"
#include "spindown/lab_settings.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/message_gate.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/web_service.hpp"

namespace {

// The command line into o; an exit code when the program ends here (--help 0, bad usage 2).
std::optional<int> parse_options(int argc, char** argv, spindown::WebServiceOptions& o) {
  CLI::App app{"spindown-web: the lab in a browser (room page, bench pages, live over Server-Sent Events)"};
  std::string listen = "127.0.0.1:8080";
  long recv_buf = spindown::services_recv_buf_bytes;
  std::vector<std::string> bench_configs;
  bool si_units = false;
  std::string lab_option, key_option;
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  app.add_option("--lab", lab_option, spindown::lab_option_help);
  app.add_option("--key", key_option, spindown::key_option_help);
  app.add_option("--recv-buf", recv_buf, "udpm receive buffer bytes added to the URL (0 = leave the URL alone)");
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
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;  // --help is 0; any bad usage is 2 (design §5)
  }
  std::string why;
  if (fd->count() == 0 && !spindown::parse_listen_address(listen, o.server.host, o.server.port, &why)) {
    fmt::print(stderr, "spindown-web: --listen: {}\n", why);
    return 2;
  }
  try {
    for (auto& [bench, file] : spindown::load_bench_files(bench_configs).files) o.lab.expected_benches.push_back(bench);
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-web: --bench-config: {}\n", e.what());
    return 2;
  }
  o.lab.lab_units = !si_units;
  if (!o.lab.is_valid(&why)) {
    fmt::print(stderr, "spindown-web: {}\n", why);
    return 2;
  }
  // Only this lab's messages, and with the lab key only signed ones (docs/security.md): the
  // others are counted and named on the pages, never shown as real.
  const auto lab = spindown::resolve_lab_settings(lab_option, key_option, &why);
  if (!lab) {
    fmt::print(stderr, "spindown-web: {}\n", why);
    return 2;
  }
  o.check = [g = std::make_shared<spindown::MessageGate>(spindown::lab_gate(*lab, o.lcm_url))](
                std::string_view channel, const void* data, std::int64_t size,
                std::int64_t recv_utime) -> std::optional<spindown::GateResult> {
    spindown::GateResult r = g->check(channel, data, size, recv_utime);
    if (r.refused()) return r;
    return std::nullopt;
  };
  fmt::print(stderr, "spindown-web: {}\n", spindown::lab_settings_text(*lab));
  o.lcm_url = spindown::with_receive_buffer(o.lcm_url, recv_buf);
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
