#include "avr_session.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <memory>
#include <poll.h>

#include "avr_board.hpp"
#include "spindown/pseudo_terminal.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/virtual_bench.hpp"

namespace spindown {

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

class AvrSession {
 public:
  AvrSession(const AvrBenchOptions& o, std::unique_ptr<EmulatedMotor> motor, std::unique_ptr<AvrBoard> board)
      : o_(o), motor_(std::move(motor)), board_(std::move(board)), pty_(plug_in_pty(o.link)),
        garble_state_(o.motor.seed), unplug_done_(o.unplug_at_s < 0) {
    std::sort(o_.reset_at_s.begin(), o_.reset_at_s.end());
  }

  int run() {
    if (!wait_reader()) return gave_up("opened");
    boot("the port was opened: DTR");
    started_ = Clock::now();
    anchor_wall_ = Clock::now();
    anchor_emu_ = board_->seconds();
    const double end_s = motor_->end_s();
    for (long step = 0; !stop_.requested() && board_->seconds() < end_s && step < 100'000'000; ++step) {
      const double now_s = board_->seconds();
      // Faults on the emulated clock.
      reset_if_due(now_s);
      if (!unplug_done_ && o_.unplug_at_s <= now_s) {
        if (!pull_the_cable(now_s)) return gave_up("reopened");
        continue;
      }
      follow_the_reader();
      if (!deliver_pending()) continue;
      if (!paced(now_s)) continue;
      if (!run_a_slice()) {
        crashed_ = true;
        break;
      }
    }
    return finish();
  }

 private:
  void unlink() const {
    std::error_code ec;
    if (!o_.link.empty()) std::filesystem::remove(o_.link, ec);
  }

  bool wait_reader() const {
    const auto deadline = Clock::now() + std::chrono::milliseconds(long(o_.wait_reader_s * 1000));
    while (!stop_.requested() && Clock::now() < deadline)
      if (pty_->wait_for_reader(std::chrono::milliseconds(100))) return true;
    return false;
  }

  // Nobody (re)opened the port in time: 1, or 0 when a stop was asked for.
  int gave_up(const char* opened) const {
    fmt::print(stderr, "spindown-avr-bench: nobody {} {} within {} s\n", opened, pty_->slave_path(), o_.wait_reader_s);
    unlink();
    return stop_.requested() ? 0 : 1;
  }

  void boot(const char* why) {
    board_->reset();
    boots_.push_back(board_->seconds());
    counter_.cut();  // bytes already on the wire stay there; the sketch's TX buffer (RAM) is gone
    fmt::print(stderr, "spindown-avr-bench: board boots at {:.3f} s emulated ({})\n", board_->seconds(), why);
  }

  void reset_if_due(double now_s) {
    if (next_reset_ < o_.reset_at_s.size() && o_.reset_at_s[next_reset_] <= now_s) {
      ++next_reset_;
      ++requested_resets_;
      boot("--reset-at");
    }
  }

  // --unplug-at: the pty goes away for --unplug-for emulated seconds, then a new one waits for
  // its reader. False when nobody opened it again.
  bool pull_the_cable(double now_s) {
    unplug_done_ = true;
    // What was produced before the pull reaches the reader first (bounded).
    const auto drain_until = Clock::now() + std::chrono::seconds(2);
    while (!pending_.empty() && Clock::now() < drain_until && pty_->reader_attached()) {
      pending_.erase(0, pty_->write(pending_, std::chrono::milliseconds(50)));
    }
    stop_.sleep_for(std::chrono::milliseconds(200));
    fmt::print(stderr, "spindown-avr-bench: cable pulled at {:.3f} s emulated for {} s\n", now_s, o_.unplug_for_s);
    counter_.drop();
    pty_.reset();
    unlink();
    // Unpowered: the motor goes on, the board's output goes nowhere.
    board_->run_until(board_->cycle() + std::uint64_t(o_.unplug_for_s * o_.f_cpu));
    board_->take_output();
    pending_.clear();
    pty_ = plug_in_pty(o_.link);
    const auto waited_from = Clock::now();
    if (!wait_reader()) return false;
    waited_s_ += std::chrono::duration<double>(Clock::now() - waited_from).count();
    boot("USB power back, the port opened");
    attached_ = true;
    anchor_wall_ = Clock::now();
    anchor_emu_ = board_->seconds();
    return true;
  }

  // The port: a reader opening it pulls DTR and resets the Uno; none there, bytes are lost.
  void follow_the_reader() {
    const bool now_attached = pty_->reader_attached();
    if (now_attached && !attached_) {
      ++reopen_resets_;
      boot("the port was opened again: DTR");
    }
    if (!now_attached && attached_) counter_.drop();
    attached_ = now_attached;
  }

  // The bytes produced and not yet accepted by the pty, to the reader (lost when none). False
  // when the reader is behind and the emulated clock was held a turn.
  bool deliver_pending() {
    if (pending_.empty()) return true;
    if (!attached_) {
      bytes_lost_ += long(pending_.size());
      pending_.clear();
      return true;
    }
    const std::size_t put = pty_->write(pending_, std::chrono::milliseconds(0));
    pending_.erase(0, put);
    if (pending_.size() <= 4096) return true;
    // The reader is behind: hold the emulated clock (the firmware cannot tell) rather
    // than lose bytes. Bounded: at most 50 ms per turn, and a stop ends it.
    const auto from = Clock::now();
    pollfd p{pty_->master_fd(), POLLOUT, 0};
    ::poll(&p, 1, 50);
    const double waited = std::chrono::duration<double>(Clock::now() - from).count();
    stalled_s_ += waited;
    anchor_wall_ += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(waited));
    return false;
  }

  // Pace: no more than `speed` emulated seconds per wall second. False when it slept instead.
  bool paced(double now_s) const {
    if (o_.speed <= 0) return true;
    const double allowed = anchor_emu_ + std::chrono::duration<double>(Clock::now() - anchor_wall_).count() * o_.speed;
    if (now_s < allowed) return true;
    stop_.sleep_for(std::chrono::microseconds(std::min<long>(5000, long((now_s - allowed) / o_.speed * 1e6) + 100)));
    return false;
  }

  // 1 ms of emulated time: the reader's bytes in, the firmware run, its UART's bytes out. False
  // when the firmware stopped.
  bool run_a_slice() {
    if (attached_) {
      const std::string in = pty_->read_available();
      if (!in.empty()) board_->send_input(in);
    }
    if (!board_->run_until(board_->cycle() + std::uint64_t(o_.f_cpu / 1000))) return false;
    std::string out = board_->take_output();
    if (out.empty()) return true;
    uart_baud_seen_ = board_->uart_baud();
    if (!attached_) {
      bytes_lost_ += long(out.size());
      return true;
    }
    const int reader = pty_->reader_baud();
    if (reader > 0 && uart_baud_seen_ > 0 && std::abs(double(reader) / uart_baud_seen_ - 1.0) > 0.045) {
      // A real UART at the wrong rate decodes framing garbage.
      out = garble_for_baud(out, uart_baud_seen_, reader, garble_state_);
      ++garbled_chunks_;
      counter_.cut();
    } else {
      counter_.feed(out);
    }
    bytes_delivered_ += long(out.size());
    pending_ += out;
    return true;
  }

  // The last bytes, the truth, the linger and the summary.
  int finish() {
    const auto drain_until = Clock::now() + std::chrono::seconds(5);
    while (!pending_.empty() && Clock::now() < drain_until && !stop_.requested() && pty_->reader_attached())
      pending_.erase(0, pty_->write(pending_, std::chrono::milliseconds(50)));
    counter_.drop();  // the pty closes after the linger: a reader drops the line the end cut short
    const double wall_s = std::chrono::duration<double>(Clock::now() - started_).count() - waited_s_;
    write_truth(wall_s);
    if (!stop_.requested()) stop_.sleep_for(std::chrono::milliseconds(long(o_.linger_s * 1000)));
    print_summary(wall_s);
    unlink();
    if (crashed_) {
      fmt::print(stderr, "spindown-avr-bench: the firmware stopped (crashed or slept with interrupts off) at {:.3f} s\n",
                 board_->seconds());
      return 1;
    }
    return 0;
  }

  void write_truth(double wall_s) const {
    if (o_.truth_file.empty()) return;
    const std::string first = counter_.first_line;
    const bool v1 = first.rfind("#spindown-v1", 0) == 0;
    nlohmann::json extra{
        {"protocol", counter_.lines == 0 ? "unknown" : (v1 ? "spindown-v1" : "lab-tsv")},
        {"baud", uart_baud_seen_},
        {"samples", counter_.samples},
        {"faults", {{"resets", requested_resets_}, {"unplugs", o_.unplug_at_s >= 0 ? 1 : 0},
                    {"reopen_resets", reopen_resets_}, {"broken_lines", counter_.broken_lines},
                    {"partial_lines", counter_.dropped_lines},
                    {"garbled_chunks", garbled_chunks_}, {"bytes_lost", bytes_lost_}}},
        {"emulator", {{"mcu", "atmega328p"}, {"f_cpu", o_.f_cpu}, {"firmware", o_.firmware},
                      {"emulated_s", board_->seconds()}, {"wall_s", wall_s},
                      {"emulated_per_wall", wall_s > 0 ? board_->seconds() / wall_s : 0.0},
                      {"speed_cap", o_.speed}, {"stalled_s", stalled_s_}, {"waited_for_reader_s", waited_s_},
                      {"lines", counter_.lines}, {"notes", counter_.notes}, {"bytes", bytes_delivered_},
                      {"adc_conversions", board_->conversions()}}}};
    std::ofstream(o_.truth_file) << motor_->truth_json(boots_, extra).dump(2) << "\n";
  }

  void print_summary(double wall_s) const {
    const double emulated_s = board_->seconds() - boots_.front();
    fmt::print(stderr,
               "spindown-avr-bench: emulated {:.2f} s in {:.2f} s of wall time: {:.2f}x real time (cap {}); "
               "{} boots, {} lines ({} samples, {} notes, {} broken), {} bytes lost with the port closed, "
               "{} garbled chunks, reader kept it waiting {:.2f} s\n",
               emulated_s, wall_s, wall_s > 0 ? emulated_s / wall_s : 0.0,
               o_.speed > 0 ? fmt::format("{}x", o_.speed) : std::string("none"), boots_.size(), counter_.lines,
               counter_.samples, counter_.notes, counter_.broken_lines, bytes_lost_, garbled_chunks_, stalled_s_);
  }

  AvrBenchOptions o_;
  std::unique_ptr<EmulatedMotor> motor_;
  std::unique_ptr<AvrBoard> board_;
  StopSignals stop_{{.ignore_sigpipe = true}};
  std::unique_ptr<PseudoTerminal> pty_;
  std::vector<double> boots_;  // emulated seconds of each boot: epoch 0, then each reset
  LineCounter counter_;
  long bytes_delivered_ = 0, bytes_lost_ = 0, garbled_chunks_ = 0, reopen_resets_ = 0, requested_resets_ = 0;
  double stalled_s_ = 0, waited_s_ = 0;
  std::uint64_t garble_state_;
  std::string pending_;  // produced, not yet accepted by the pty
  int uart_baud_seen_ = 0;
  Clock::time_point started_, anchor_wall_;
  double anchor_emu_ = 0;
  bool attached_ = true;
  bool unplug_done_;
  std::size_t next_reset_ = 0;
  bool crashed_ = false;
};

}  // namespace

int run_avr_bench(const AvrBenchOptions& o) {
  std::unique_ptr<EmulatedMotor> motor;
  std::unique_ptr<AvrBoard> board;
  try {
    motor = std::make_unique<EmulatedMotor>(o.motor);
    board = std::make_unique<AvrBoard>(o.firmware, std::uint32_t(o.f_cpu),
                                       [m = motor.get()](double t) { return m->convert(t); });
  } catch (const std::exception& e) {
    fmt::print(stderr, "spindown-avr-bench: {}\n", e.what());
    return 2;
  }
  return AvrSession(o, std::move(motor), std::move(board)).run();
}

}  // namespace spindown
