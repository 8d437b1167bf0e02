// spindown: offline analysis of spin-down recordings (design §5).
// Exit codes: 0 ok, 1 a file or run could not be used, 2 bad usage.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "baseline_command.hpp"
#include "exit_codes.hpp"
#include "explain_command.hpp"
#include "fit_command.hpp"
#include "keygen_command.hpp"
#include "refit_command.hpp"
#include "export_command.hpp"
#include "watch_command.hpp"
#include "report_command.hpp"
#include "doctor_command.hpp"
#include "simulate_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"spindown: fit friction models to DC-motor spin-down recordings"};
  app.require_subcommand(1);
  spindown::cli::setup_fit(app);
  spindown::cli::setup_explain(app);
  spindown::cli::setup_refit(app);
  spindown::cli::setup_export(app);
  spindown::cli::setup_watch(app);
  spindown::cli::setup_baseline(app);
  spindown::cli::setup_report(app);
  spindown::cli::setup_doctor(app);
  spindown::cli::setup_simulate(app);
  spindown::cli::setup_keygen(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::RuntimeError& e) {  // a subcommand finished with a non-zero exit code
    return e.get_exit_code();
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help, or the usage error
    return code == 0 ? 0 : spindown::cli::exit_bad_usage;
  } catch (const std::exception& e) {  // a bug: say so rather than abort
    std::cerr << "spindown: internal error: " << e.what() << '\n';
    return spindown::cli::exit_unusable;
  }
  return spindown::cli::exit_ok;
}
