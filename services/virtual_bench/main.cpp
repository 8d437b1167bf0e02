// spindown-virtual-bench: a simulated bench on a pseudo-terminal. Prints the pty's path (and
// links it with --link), waits for a reader (as an Arduino boots when its port opens), then
// writes the runs at the baud rate's pace, --speed times faster. Exits when all runs are sent.
#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>

#include "spindown/pseudo_terminal.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/virtual_bench.hpp"
#include "spindown/virtual_bench_cli.hpp"

namespace {

using Clock = std::chrono::steady_clock;


}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-virtual-bench: a simulated spin-down bench on a pseudo-terminal"};
  spindown::VirtualBenchOptions o;
  spindown::VirtualBenchCli cli;
  std::string link, truth_file, sent_file;
  double speed = 1.0, wait_reader_s = 30, linger_s = 1.0;
  app.set_config("--config", "", "TOML file with any of these options (key = long option name)");
  spindown::add_virtual_bench_options(app, o, cli);
  app.add_option("--baud", o.baud, "baud rate (default 9600 lab, 115200 spindown-v1)");
  app.add_option("--speed", speed, "times faster than real time; 0 = as fast as possible")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--link", link, "symlink to the pty's path (like /dev/ttyACM0)");
  app.add_option("--truth", truth_file, "write parameters, cut/stop times and faults as JSON");
  app.add_option("--sent", sent_file, "write every sample line sent (TSV: epoch device_time_us value raw_adc device_seq)");
  app.add_option("--wait-reader", wait_reader_s, "seconds to wait for a reader to open the pty (0: do not wait)");
  app.add_option("--linger", linger_s, "seconds to keep the pty open after the last line");
  CLI11_PARSE(app, argc, argv);

  spindown::apply_virtual_bench_cli(cli, o);

  std::unique_ptr<spindown::VirtualBench> bench;
  try {
    bench = std::make_unique<spindown::VirtualBench>(o);
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-virtual-bench: {}\n", e.what());
    return 2;
  }
  if (!truth_file.empty()) std::ofstream(truth_file) << bench->truth().dump(2) << "\n";
  if (!sent_file.empty()) {
    std::ofstream out(sent_file);
    out << "epoch\tdevice_time_us\tvalue\traw_adc\tdevice_seq\n";
    for (const auto& s : bench->sent())
      out << fmt::format("{}\t{}\t{:.17g}\t{}\t{}\n", s.epoch, s.device_time_us, s.value, s.raw_adc, s.device_seq);
  }

  spindown::StopSignals stop({.ignore_sigpipe = true});
  auto pty = spindown::plug_in_pty(link);

  const auto wait_reader = [&]() {
    if (wait_reader_s <= 0) return true;
    const auto deadline = Clock::now() + std::chrono::milliseconds(long(wait_reader_s * 1000));
    while (!stop.requested() && Clock::now() < deadline)
      if (pty->wait_for_reader(std::chrono::milliseconds(100))) return true;
    return false;
  };
  const auto unlink = [&]() {
    std::error_code ec;
    if (!link.empty()) std::filesystem::remove(link, ec);
  };
  if (!wait_reader()) {
    fmt::print(stderr, "spindown-virtual-bench: nobody opened {} within {} s\n", pty->slave_path(), wait_reader_s);
    unlink();
    return stop.requested() ? 0 : 1;
  }

  const int baud = o.effective_baud();
  std::uint64_t garble_state = o.seed;
  auto anchor = Clock::now();  // bench time 0
  auto at = [&](double bench_s) {
    return anchor + std::chrono::microseconds(speed > 0 ? long(bench_s / speed * 1e6) : 0L);
  };
  long written = 0, dropped = 0, garbled = 0;
  for (const auto& e : bench->emissions()) {
    if (stop.requested()) break;
    if (e.kind == spindown::BenchEmission::Kind::unplug) {
      stop.sleep_until(at(e.wire_s));
      // What was sent before the pull reached the host (the reader may be a little behind):
      // let it drain, so "sent" means "delivered" and tests can compare sample for sample.
      stop.sleep_until(Clock::now() + std::chrono::milliseconds(200));
      fmt::print(stderr, "spindown-virtual-bench: cable pulled for {} s\n", e.unplug_for_s);
      pty.reset();
      if (!link.empty()) std::filesystem::remove(link);
      const auto back = Clock::now() + std::chrono::milliseconds(long(e.unplug_for_s * 1000 / (speed > 0 ? speed : 1e9)));
      stop.sleep_until(back);
      pty = spindown::plug_in_pty(link);
      const auto waited_from = Clock::now();
      if (!wait_reader()) {
        fmt::print(stderr, "spindown-virtual-bench: nobody reopened {} within {} s\n", pty->slave_path(), wait_reader_s);
        unlink();
        return stop.requested() ? 0 : 1;
      }
      anchor += Clock::now() - waited_from;  // the board boots when the port opens
      continue;
    }
    stop.sleep_until(at(e.wire_s));
    std::string_view bytes = e.bytes;
    std::string garbage;
    const int reader = pty->reader_baud();
    if (reader > 0 && reader != baud) {  // a real UART at the wrong rate decodes framing garbage
      garbage = spindown::garble_for_baud(bytes, baud, reader, garble_state);
      bytes = garbage;
      ++garbled;
    }
    const bool attached = pty->reader_attached();
    const auto timeout = std::chrono::milliseconds(attached ? 2000 + long(bytes.size() / 1000) : 0);
    const auto put = pty->write(bytes, timeout);
    if (put < bytes.size()) ++dropped;
    else ++written;
  }
  if (!stop.requested()) stop.sleep_until(Clock::now() + std::chrono::milliseconds(long(linger_s * 1000)));
  fmt::print(stderr, "spindown-virtual-bench: {} lines written, {} dropped (no reader), {} garbled (baud mismatch)\n",
             written, dropped, garbled);
  unlink();
  return 0;
}
