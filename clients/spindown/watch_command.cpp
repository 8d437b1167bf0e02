#include "watch_command.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <deque>
#include <exception>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <regex>
#include <sys/ioctl.h>
#include <unistd.h>

#include "exit_codes.hpp"
#include "spindown/lab_table.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/message_decode.hpp"

namespace spindown::cli {

namespace {

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop = true; }

std::int64_t wall_us() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string clock_text(std::int64_t utime) {
  const std::time_t s = static_cast<std::time_t>(utime / 1000000);
  std::tm local{};
  ::localtime_r(&s, &local);
  return fmt::format("{:02}:{:02}:{:02}.{}", local.tm_hour, local.tm_min, local.tm_sec, (utime / 100000) % 10);
}

std::size_t terminal_width() {
  winsize ws{};
  if (::ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0) return ws.ws_col;
  return 0;
}

// Decodes the suite's channels into the table; never lets an exception reach LCM's C callback.
class WatchListener {
 public:
  WatchListener(LabTable& table, const std::string& bench_regex) : table_(table), wanted_(bench_regex) {}

  // LCM's C callback (the C++ wrapper's member-function subscriptions trip UBSan inside LCM
  // 1.3.1's header, as spindown-fitter found).
  static void on_lcm(const lcm_recv_buf_t* rbuf, const char* channel, void* user) {
    auto* self = static_cast<WatchListener*>(user);
    try {
      self->handle(rbuf, channel);
    } catch (const std::exception& e) {
      self->table_.on_bad_message(fmt::format("{}: {}", channel, e.what()), rbuf->recv_utime);
    }
  }

 private:
  template <class Message>
  bool decode(const lcm_recv_buf_t* rbuf, const std::string& channel, Message& m, const char* type) {
    // decode_message checks the layout first: a hostile packet cannot make it allocate gigabytes.
    const auto size = static_cast<std::int64_t>(rbuf->data_size);
    std::string why;
    if (decode_message(m, rbuf->data, size, &why)) return true;
    table_.on_bad_message(fmt::format("{}: {} bytes that do not decode as {}: {}", channel, size, type, why),
                          rbuf->recv_utime);
    return false;
  }

  void handle(const lcm_recv_buf_t* rbuf, const std::string& channel) {
    const auto parsed = parse_channel(channel);
    if (!parsed) return;
    const std::string& id = parsed->bench;
    const std::int64_t now = rbuf->recv_utime > 0 ? rbuf->recv_utime : wall_us();
    const bool bench_wanted = std::regex_match(id, wanted_);
    switch (parsed->kind) {
      case ChannelKind::sample:
        if (samples_t m; bench_wanted && decode(rbuf, channel, m, "samples_t")) table_.on_samples(id, m, now);
        break;
      case ChannelKind::config:
        if (config_t m; bench_wanted && decode(rbuf, channel, m, "config_t")) table_.on_config(id, m, now);
        break;
      case ChannelKind::run:
        if (run_t m; bench_wanted && decode(rbuf, channel, m, "run_t")) table_.on_run(id, m, now);
        break;
      case ChannelKind::fit:
        if (fit_t m; bench_wanted && decode(rbuf, channel, m, "fit_t")) table_.on_fit(id, m, now);
        break;
      case ChannelKind::status:
        // A bridge's heartbeat belongs to its bench (filtered); services are always shown.
        if (status_t m; decode(rbuf, channel, m, "status_t") && (m.service != "bridge" || bench_wanted))
          table_.on_status(id, m, now);
        break;
      case ChannelKind::explain:
        break;
    }
  }

  LabTable& table_;
  std::regex wanted_;
};

void print(const std::string& text) {
  std::fputs(text.c_str(), stdout);
  std::fflush(stdout);
}

}  // namespace

void setup_watch(CLI::App& app) {
  auto opt = std::make_shared<WatchCommandOptions>();
  CLI::App* sub = app.add_subcommand("watch", "Live table of the lab's benches: run state, last fit, bridge health");
  sub->footer(
      "Listens to SPINDOWN.<bench>.SAMPLE|CONFIG|RUN|FIT|STATUS and the services' STATUS. On a terminal the table is "
      "redrawn in place; with --plain or when stdout is not a terminal, events (runs, fits, bridge changes, "
      "sequence gaps) are printed as lines and the table every --interval when something changed, and once more at "
      "the end. AGE marked '!' is older than 5 s. SEQ GAPS are samples_t.seq gaps as this listener saw them.\n"
      "Exit codes: 0 stopped by SIGINT/SIGTERM or after --duration, 1 LCM could not start, 2 bad usage.");
  sub->add_option("--bench", opt->bench_regex, "Only benches whose id matches this regex (default all)");
  sub->add_option("--lcm-url", opt->lcm_url, "LCM URL (default: LCM_DEFAULT_URL or LCM's default)");
  auto* once = sub->add_flag("--once", opt->once, "Listen for --duration (default 3 s), print one table and exit");
  sub->add_option("--duration", opt->duration_s, "Stop after this many seconds (default: until SIGINT/SIGTERM)")
      ->check(CLI::PositiveNumber);
  sub->add_flag("--plain", opt->plain, "Append-only lines even on a terminal (no screen redraw)");
  sub->add_option("--interval", opt->interval_s,
                  "Seconds between redraws (default 1 on a terminal; 10 with --plain, only when something changed)")
      ->check(CLI::Range(0.05, 3600.0));
  sub->add_flag("--lab-units", opt->lab_units, "Coefficients in the lab's units (g·cm²·s⁻¹, g·cm²·rad·s⁻²)");
  sub->add_flag("--no-events", opt->no_events, "With --plain: tables only, no event lines")->excludes(once);
  sub->callback([opt]() {
    try {
      std::regex check(opt->bench_regex);
    } catch (const std::regex_error& e) {
      throw CLI::ValidationError(fmt::format("--bench: not a regex: '{}': {}", opt->bench_regex, e.what()));
    }
    const int code = run_watch(*opt);
    if (code != exit_ok) throw CLI::RuntimeError(code);
  });
}

int run_watch(const WatchCommandOptions& o) {
  lcm::LCM lcm(o.lcm_url);
  if (!lcm.good()) {
    std::fprintf(stderr, "spindown watch: cannot start LCM%s%s\n", o.lcm_url.empty() ? "" : " at ",
                 o.lcm_url.c_str());
    return exit_unusable;
  }
  LabTableOptions topt;
  topt.lab_units = o.lab_units;
  LabTable table(topt);
  WatchListener listener(table, o.bench_regex);
  lcm_t* raw = lcm.getUnderlyingLCM();
  lcm_subscription_t* sub = lcm_subscribe(raw, "SPINDOWN\\..*", &WatchListener::on_lcm, &listener);
  if (!sub) {
    std::fprintf(stderr, "spindown watch: cannot subscribe to SPINDOWN\\..*\n");
    return exit_unusable;
  }
  lcm_subscription_set_queue_capacity(sub, 10000);  // LCM's default of 30 drops silently in a burst (design §7)

  g_stop = false;
  struct sigaction sa{};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a signal ends the wait at once
  struct sigaction old_int{}, old_term{};
  sigaction(SIGINT, &sa, &old_int);
  sigaction(SIGTERM, &sa, &old_term);

  const bool tty = ::isatty(STDOUT_FILENO) == 1;
  const bool redraw = tty && !o.plain && !o.once;
  const double duration = o.duration_s > 0 ? o.duration_s : (o.once ? 3.0 : 0.0);
  const double interval = o.interval_s > 0 ? o.interval_s : (redraw ? 1.0 : 10.0);
  const std::int64_t start = wall_us();
  const std::int64_t end = duration > 0 ? start + static_cast<std::int64_t>(duration * 1e6) : std::numeric_limits<std::int64_t>::max();
  const auto interval_us = static_cast<std::int64_t>(interval * 1e6);
  std::int64_t next_table = redraw ? start : start + interval_us;
  std::deque<std::string> recent;  // events shown under a redrawn table
  constexpr std::size_t recent_shown = 12;

  if (!redraw && !o.once)
    print(fmt::format("spindown watch: listening{}{} (benches matching '{}')\n", o.lcm_url.empty() ? "" : " on ",
                      o.lcm_url, o.bench_regex));
  int lcm_failures = 0;
  for (;;) {
    const std::int64_t now = wall_us();
    if (g_stop || now >= end) break;
    const int wait_ms = static_cast<int>(std::clamp<std::int64_t>((std::min(next_table, end) - now) / 1000, 1, 100));
    if (lcm.handleTimeout(wait_ms) < 0 && !g_stop) {
      if (++lcm_failures > 50) {
        std::fprintf(stderr, "spindown watch: LCM keeps failing to receive; stopping\n");
        break;
      }
    }
    const std::int64_t t = wall_us();
    for (auto& e : table.take_events()) {
      std::string line = clock_text(t) + "  " + e;
      if (redraw) {
        recent.push_back(std::move(line));
        if (recent.size() > recent_shown) recent.pop_front();
      } else if (!o.once && !o.no_events) {
        print(line + '\n');
      }
    }
    if (o.once || t < next_table) continue;
    next_table = t + interval_us;
    if (redraw) {
      std::string screen = "\x1b[H\x1b[2J" + table.render(t, terminal_width());
      if (!recent.empty()) {
        screen += "\nrecent events:\n";
        for (const auto& line : recent) screen += "  " + line + '\n';
      }
      print(screen);
    } else if (table.changed()) {
      print('\n' + table.render(t) + '\n');
      table.clear_changed();
    }
  }
  lcm_unsubscribe(raw, sub);
  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  // The last state stays on screen (a redraw) or closes the log (plain, --once).
  const std::int64_t t = wall_us();
  if (redraw) {
    std::string screen = "\x1b[H\x1b[2J" + table.render(t, terminal_width());
    if (!recent.empty()) {
      screen += "\nrecent events:\n";
      for (const auto& line : recent) screen += "  " + line + '\n';
    }
    print(screen);
  } else {
    if (!o.once && !o.no_events)
      for (auto& e : table.take_events()) print(clock_text(t) + "  " + e + '\n');
    print((o.once ? "" : "\n") + table.render(t));
  }
  return exit_ok;
}

}  // namespace spindown::cli
