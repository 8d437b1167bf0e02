// spindown-avr-bench: a compiled bench sketch on an emulated Arduino Uno (simavr, ATmega328P at
// 16 MHz), its UART on a pseudo-terminal like a USB serial port, A0 driven by spindown's motor
// simulator on the emulated clock. Prints the pty's path (and links it with --link), waits for
// a reader (the Uno boots when its port is opened), runs the motor's runs and exits.
// services/avr_bench/README.md says what it models and how time is paced.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <poll.h>

#include "avr_board.hpp"
#include "spindown/emulated_motor.hpp"
#include "spindown/pseudo_terminal.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/virtual_bench.hpp"
#include "spindown/virtual_bench_cli.hpp"

namespace {

using Clock = std::chrono::steady_clock;


// What reached the reader, line by line: a line is a sample, a banner/note ('#'), or broken (a
// reset cut it, or the port was reopened inside it).
struct LineCounter {
  long lines = 0, samples = 0, notes = 0, broken_lines = 0;
  std::size_t len = 0;
  char first = 0;
  bool broken = false;
  std::string first_line;
  void feed(std::string_view bytes) {
    for (const char c : bytes) {
      if (c == '\n') {
        if (broken) ++broken_lines;
        else if (len > 0) {
          ++lines;
          (first == '#' ? notes : samples) += 1;
        }
        len = 0;
        broken = false;
        continue;
      }
      if (c == '\r') continue;
      if (len++ == 0) first = c;
      if (lines == 0 && first_line.size() < 200 && !broken) first_line += c;
    }
  }
  void cut() {  // a reset mid-line: what was sent of it and the next line's bytes form one bad line
    if (len > 0) broken = true;
  }
  void drop() {  // the port went away mid-line: the reader drops what it had of it
    if (len > 0) ++dropped_lines;
    len = 0;
    broken = false;
  }
  long dropped_lines = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-avr-bench: a bench sketch on an emulated Arduino Uno (simavr), UART on a pty, A0 from the motor simulator"};
  spindown::EmulatedMotorOptions m;
  std::string firmware, link, truth_file, lead_in = "zeros";
  double speed = 1.0, wait_reader_s = 30, linger_s = 1.0, unplug_at_s = -1, unplug_for_s = 1.0;
  double f_cpu = 16e6;
  std::vector<double> reset_at_s;
  app.add_option("--firmware", firmware, "the sketch: .elf or .hex from deploy/firmware (make -C deploy/firmware)")->required();
  app.add_option("--link", link, "symlink to the pty's path (like /dev/ttyACM0)");
  app.add_option("--truth", truth_file, "write parameters, cut/stop times, resets and the emulator's speed as JSON");
  app.add_option("--speed", speed, "at most this many emulated seconds per wall second; 0 = as fast as the emulator runs")
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--wait-reader", wait_reader_s, "seconds to wait for a reader to open the pty");
  app.add_option("--linger", linger_s, "seconds to keep the pty open after the last run");
  app.add_option("--f-cpu", f_cpu, "crystal (Hz)")->check(CLI::Range(1e6, 32e6));
  app.add_option("--runs", m.runs, "runs: powered, cut, coast, stop, rest");
  app.add_option("--first-run-s", m.first_run_s, "emulated seconds from the first boot to the first run");
  app.add_option("--lead-in-s", m.lead_in_s, "seconds powered before each cut");
  app.add_option("--lead-in", lead_in, "what A0 reads while powered")->check(CLI::IsMember({"zeros", "supply"}));
  app.add_option("--supply", m.supply_v, "A0 while powered with --lead-in supply (V)");
  app.add_option("--tail-s", m.tail_s, "seconds at rest after each stop");
  app.add_option("--idle", m.idle_s, "more seconds at rest before the next run");
  app.add_option("--max-coast-s", m.max_coast_s, "longest coast");
  app.add_option("--e0", m.e0_v, "back-EMF at the cut (V)");
  app.add_option("--e0-step", m.e0_step_v, "added to e0 at each further run (V)");
  spindown::add_motor_options(app, m.bench, m.friction);
  app.add_option("--noise", m.noise_v, "white noise on A0 (V)");
  app.add_option("--seed", m.seed, "random seed of the noise");
  app.add_option("--reset-at", reset_at_s, "emulated seconds at which the board resets (reset button, a DTR pulse; repeatable)");
  app.add_option("--unplug-at", unplug_at_s, "emulated seconds at which the USB cable is pulled (the pty goes away)");
  app.add_option("--unplug-for", unplug_for_s, "emulated seconds it stays out (then a new pty; the board boots when it is opened)");
  CLI11_PARSE(app, argc, argv);
  m.lead_in_supply = lead_in == "supply";
  m.adc_bits = 10;
  m.adc_ref_v = 5.0;

  std::unique_ptr<spindown::EmulatedMotor> motor;
  std::unique_ptr<spindown::AvrBoard> board;
  try {
    motor = std::make_unique<spindown::EmulatedMotor>(m);
    board = std::make_unique<spindown::AvrBoard>(firmware, std::uint32_t(f_cpu),
                                                 [&motor](double t) { return motor->convert(t); });
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-avr-bench: {}\n", e.what());
    return 2;
  }
  std::sort(reset_at_s.begin(), reset_at_s.end());

  spindown::StopSignals stop({.ignore_sigpipe = true});
  auto pty = spindown::plug_in_pty(link);

  const auto unlink = [&]() {
    std::error_code ec;
    if (!link.empty()) std::filesystem::remove(link, ec);
  };
  const auto wait_reader = [&]() {
    const auto deadline = Clock::now() + std::chrono::milliseconds(long(wait_reader_s * 1000));
    while (!stop.requested() && Clock::now() < deadline)
      if (pty->wait_for_reader(std::chrono::milliseconds(100))) return true;
    return false;
  };

  std::vector<double> boots;  // emulated seconds of each boot: epoch 0, then each reset
  LineCounter counter;
  long bytes_delivered = 0, bytes_lost = 0, garbled_chunks = 0, reopen_resets = 0, requested_resets = 0;
  double stalled_s = 0, waited_s = 0;
  std::uint64_t garble_state = m.seed;
  std::string pending;  // produced, not yet accepted by the pty
  int uart_baud_seen = 0;

  const auto boot = [&](const char* why) {
    board->reset();
    boots.push_back(board->seconds());
    counter.cut();  // bytes already on the wire stay there; the sketch's TX buffer (RAM) is gone
    fmt::print(stderr, "spindown-avr-bench: board boots at {:.3f} s emulated ({})\n", board->seconds(), why);
  };
  const auto write_truth = [&](double wall_s) {
    if (truth_file.empty()) return;
    const std::string first = counter.first_line;
    const bool v1 = first.rfind("#spindown-v1", 0) == 0;
    nlohmann::json extra{
        {"protocol", counter.lines == 0 ? "unknown" : (v1 ? "spindown-v1" : "lab-tsv")},
        {"baud", uart_baud_seen},
        {"samples", counter.samples},
        {"faults", {{"resets", requested_resets}, {"unplugs", unplug_at_s >= 0 ? 1 : 0},
                    {"reopen_resets", reopen_resets}, {"broken_lines", counter.broken_lines},
                    {"partial_lines", counter.dropped_lines},
                    {"garbled_chunks", garbled_chunks}, {"bytes_lost", bytes_lost}}},
        {"emulator", {{"mcu", "atmega328p"}, {"f_cpu", f_cpu}, {"firmware", firmware},
                      {"emulated_s", board->seconds()}, {"wall_s", wall_s},
                      {"emulated_per_wall", wall_s > 0 ? board->seconds() / wall_s : 0.0},
                      {"speed_cap", speed}, {"stalled_s", stalled_s}, {"waited_for_reader_s", waited_s},
                      {"lines", counter.lines}, {"notes", counter.notes}, {"bytes", bytes_delivered},
                      {"adc_conversions", board->conversions()}}}};
    std::ofstream(truth_file) << motor->truth_json(boots, extra).dump(2) << "\n";
  };

  if (!wait_reader()) {
    fmt::print(stderr, "spindown-avr-bench: nobody opened {} within {} s\n", pty->slave_path(), wait_reader_s);
    unlink();
    return stop.requested() ? 0 : 1;
  }
  boot("the port was opened: DTR");
  const auto started = Clock::now();
  auto anchor_wall = Clock::now();
  double anchor_emu = board->seconds();
  bool attached = true;
  bool unplug_done = unplug_at_s < 0;
  std::size_t next_reset = 0;
  const auto slice = std::uint64_t(f_cpu / 1000);  // 1 ms of emulated time per step
  bool crashed = false;
  const double end_s = motor->end_s();

  for (long step = 0; !stop.requested() && board->seconds() < end_s && step < 100'000'000; ++step) {
    const double now_s = board->seconds();
    // Faults on the emulated clock.
    if (next_reset < reset_at_s.size() && reset_at_s[next_reset] <= now_s) {
      ++next_reset;
      ++requested_resets;
      boot("--reset-at");
    }
    if (!unplug_done && unplug_at_s <= now_s) {
      unplug_done = true;
      // What was produced before the pull reaches the reader first (bounded).
      const auto drain_until = Clock::now() + std::chrono::seconds(2);
      while (!pending.empty() && Clock::now() < drain_until && pty->reader_attached()) {
        pending.erase(0, pty->write(pending, std::chrono::milliseconds(50)));
      }
      stop.sleep_for(std::chrono::milliseconds(200));
      fmt::print(stderr, "spindown-avr-bench: cable pulled at {:.3f} s emulated for {} s\n", now_s, unplug_for_s);
      counter.drop();
      pty.reset();
      unlink();
      // Unpowered: the motor goes on, the board's output goes nowhere.
      board->run_until(board->cycle() + std::uint64_t(unplug_for_s * f_cpu));
      board->take_output();
      pending.clear();
      pty = spindown::plug_in_pty(link);
      const auto waited_from = Clock::now();
      if (!wait_reader()) {
        fmt::print(stderr, "spindown-avr-bench: nobody reopened {} within {} s\n", pty->slave_path(), wait_reader_s);
        unlink();
        return stop.requested() ? 0 : 1;
      }
      waited_s += std::chrono::duration<double>(Clock::now() - waited_from).count();
      boot("USB power back, the port opened");
      attached = true;
      anchor_wall = Clock::now();
      anchor_emu = board->seconds();
      continue;
    }
    // The port: a reader opening it pulls DTR and resets the Uno; none there, bytes are lost.
    const bool now_attached = pty->reader_attached();
    if (now_attached && !attached) {
      ++reopen_resets;
      boot("the port was opened again: DTR");
    }
    if (!now_attached && attached) counter.drop();
    attached = now_attached;
    if (!pending.empty()) {
      if (!attached) {
        bytes_lost += long(pending.size());
        pending.clear();
      } else {
        const std::size_t put = pty->write(pending, std::chrono::milliseconds(0));
        pending.erase(0, put);
        if (pending.size() > 4096) {
          // The reader is behind: hold the emulated clock (the firmware cannot tell) rather
          // than lose bytes. Bounded: at most 50 ms per turn, and a stop ends it.
          const auto from = Clock::now();
          pollfd p{pty->master_fd(), POLLOUT, 0};
          ::poll(&p, 1, 50);
          const double waited = std::chrono::duration<double>(Clock::now() - from).count();
          stalled_s += waited;
          anchor_wall += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(waited));
          continue;
        }
      }
    }
    // Pace: no more than `speed` emulated seconds per wall second.
    if (speed > 0) {
      const double allowed = anchor_emu + std::chrono::duration<double>(Clock::now() - anchor_wall).count() * speed;
      if (now_s >= allowed) {
        stop.sleep_for(std::chrono::microseconds(std::min<long>(5000, long((now_s - allowed) / speed * 1e6) + 100)));
        continue;
      }
    }
    if (attached) {
      const std::string in = pty->read_available();
      if (!in.empty()) board->send_input(in);
    }
    if (!board->run_until(board->cycle() + slice)) {
      crashed = true;
      break;
    }
    std::string out = board->take_output();
    if (out.empty()) continue;
    uart_baud_seen = board->uart_baud();
    if (!attached) {
      bytes_lost += long(out.size());
      continue;
    }
    const int reader = pty->reader_baud();
    if (reader > 0 && uart_baud_seen > 0 && std::abs(double(reader) / uart_baud_seen - 1.0) > 0.045) {
      // A real UART at the wrong rate decodes framing garbage.
      out = spindown::garble_for_baud(out, uart_baud_seen, reader, garble_state);
      ++garbled_chunks;
      counter.cut();
    } else {
      counter.feed(out);
    }
    bytes_delivered += long(out.size());
    pending += out;
  }
  // The last bytes, then linger.
  const auto drain_until = Clock::now() + std::chrono::seconds(5);
  while (!pending.empty() && Clock::now() < drain_until && !stop.requested() && pty->reader_attached())
    pending.erase(0, pty->write(pending, std::chrono::milliseconds(50)));
  counter.drop();  // the pty closes after the linger: a reader drops the line the end cut short
  const double wall_s = std::chrono::duration<double>(Clock::now() - started).count() - waited_s;
  write_truth(wall_s);
  if (!stop.requested()) stop.sleep_for(std::chrono::milliseconds(long(linger_s * 1000)));
  fmt::print(stderr,
             "spindown-avr-bench: emulated {:.2f} s in {:.2f} s of wall time: {:.2f}x real time (cap {}); "
             "{} boots, {} lines ({} samples, {} notes, {} broken), {} bytes lost with the port closed, "
             "{} garbled chunks, reader kept it waiting {:.2f} s\n",
             board->seconds() - boots.front(), wall_s, wall_s > 0 ? (board->seconds() - boots.front()) / wall_s : 0.0,
             speed > 0 ? fmt::format("{}x", speed) : std::string("none"), boots.size(), counter.lines, counter.samples,
             counter.notes, counter.broken_lines, bytes_lost, garbled_chunks, stalled_s);
  unlink();
  if (crashed) {
    fmt::print(stderr, "spindown-avr-bench: the firmware stopped (crashed or slept with interrupts off) at {:.3f} s\n",
               board->seconds());
    return 1;
  }
  return 0;
}
