#include "simulate_command.hpp"

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include "exit_codes.hpp"

namespace spindown::cli {

void setup_simulate(CLI::App& app) {
  auto opt = std::make_shared<SimulateCommandOptions>();
  CLI::App* sub = app.add_subcommand(
      "simulate", "Write what the lab's Arduino would print for simulated spin-down runs (known-answer recordings)");
  sub->footer("Exit codes: 0 ok, 1 a file could not be written, 2 bad usage (an existing -o file is refused).");
  sub->add_option("-o,--output", opt->out, "The recording to write (default: stdout)");
  sub->add_option("--truth", opt->truth, "Also write the parameters, each run's cut and stop, and the faults (JSON)");
  sub->add_flag("--putty-header", opt->putty_header, "Start with a PuTTY log's header line, as the lab's logs do");
  add_virtual_bench_options(*sub, opt->bench, opt->bench_cli);
  sub->callback([opt]() {
    const int code = run_simulate(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_simulate(SimulateCommandOptions o) {
  apply_virtual_bench_cli(o.bench_cli, o.bench);
  const bool to_stdout = o.out.empty() || o.out == "-";
  for (const std::string& path : {to_stdout ? std::string() : o.out, o.truth})
    if (!path.empty() && std::filesystem::exists(path)) {
      std::cerr << fmt::format("spindown simulate: {}: the file exists (refused: choose a new name)\n", path);
      return exit_bad_usage;
    }
  std::unique_ptr<VirtualBench> bench;
  try {
    bench = std::make_unique<VirtualBench>(o.bench);
  } catch (const std::exception& e) {
    std::cerr << fmt::format("spindown simulate: {}\n", e.what());
    return exit_bad_usage;
  }
  std::string text;
  if (o.putty_header) {
    text += putty_log_header;
    // PuTTY starts logging mid-line: the first line is the end of the one before the first
    // whole sample (the lab's logs begin "3<TAB>0.00"; readers drop it as cut short).
    for (const BenchEmission& e : bench->emissions())
      if (e.kind == BenchEmission::Kind::sample && o.bench.protocol == BenchProtocol::lab) {
        const std::size_t tab = e.bytes.find('\t');
        if (tab != std::string::npos && tab > 0) {
          const long first_ms = std::atol(e.bytes.substr(0, tab).c_str());
          const long before_ms = first_ms - std::lround(o.bench.spec.period_s * 1000.0);
          text += std::to_string(before_ms).back() + e.bytes.substr(tab);
        }
        break;
      }
  }
  for (const BenchEmission& e : bench->emissions()) text += e.bytes;
  if (to_stdout) std::cout << text << std::flush;
  // The recording and its truth, both or neither: each is written beside its name and renamed
  // into place once both are complete (a half-written recording would read as a damaged one,
  // and a recording without its truth would block the retry, since -o never overwrites).
  std::vector<std::pair<std::string, std::string>> files;  // name, bytes
  if (!to_stdout) files.emplace_back(o.out, std::move(text));
  if (!o.truth.empty()) files.emplace_back(o.truth, bench->truth().dump(2) + "\n");
  const auto remove_parts = [&] {
    std::error_code ec;
    for (const auto& [path, bytes] : files) std::filesystem::remove(path + ".part", ec);
  };
  for (const auto& [path, bytes] : files) {
    std::ofstream f(path + ".part", std::ios::binary | std::ios::trunc);
    if (f) f << bytes;
    if (!f || !f.flush()) {
      std::cerr << fmt::format("spindown simulate: {}: cannot write: {}\n", path, std::strerror(errno));
      remove_parts();
      return exit_unusable;
    }
  }
  for (const auto& [path, bytes] : files) {
    std::error_code ec;
    std::filesystem::rename(path + ".part", path, ec);
    if (ec) {
      std::cerr << fmt::format("spindown simulate: {}: cannot write: {}\n", path, ec.message());
      remove_parts();
      return exit_unusable;
    }
  }
  return exit_ok;
}

}  // namespace spindown::cli
