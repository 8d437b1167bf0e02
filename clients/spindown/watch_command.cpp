#include "watch_command.hpp"

#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <deque>
#include <exception>
#include <fmt/format.h>
#include <memory>
#include <regex>
#include <vector>
#include <sys/ioctl.h>
#include <unistd.h>

#include "exit_codes.hpp"
#include "spindown/clock.hpp"
#include "spindown/lab_table.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/stop_signal.hpp"
#include "spindown/watch_screen.hpp"

namespace spindown::cli {

namespace {

std::string clock_text(std::int64_t utime) {
  const std::time_t s = static_cast<std::time_t>(utime / 1000000);
  std::tm local{};
  ::localtime_r(&s, &local);
  return fmt::format("{:02}:{:02}:{:02}.{}", local.tm_hour, local.tm_min, local.tm_sec, (utime / 100000) % 10);
}

// The terminal's size now (it may have been resized): columns and rows, 0 when unknown.
WatchScreenOptions terminal_size() {
  WatchScreenOptions size;
  winsize ws{};
  if (::ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0) {
    size.width = ws.ws_col;
    size.height = ws.ws_row;
  }
  return size;
}

// The table hears SPINDOWN.<bench>.<KIND> as Msg: table_call(bench id, message, receive time).
// A channel whose name is not the suite's is ignored, and so is (before decoding) a bench the
// --bench regex does not want, unless every bench is kept (the services' heartbeats).
// Before the table sees a message, the gate: another lab's (and with --key an unsigned, wrongly
// signed or replayed one) is counted and named as not shown, never shown as data.
template <class Msg, class TableCall>
bool listen(LcmLoop& loop, ChannelKind kind, const std::regex& wanted, bool every_bench, MessageGate& gate,
            LabTable& table, TableCall table_call) {
  LcmSubscribeOptions options;
  options.queue_capacity = 10000;  // LCM's default of 30 drops silently in a burst (design §7)
  options.accept = [kind, &wanted, every_bench](std::string_view channel) {
    const auto parsed = parse_channel(channel);
    return parsed && parsed->kind == kind && (every_bench || std::regex_match(parsed->bench, wanted));
  };
  return loop.subscribe<Msg>(
      fmt::format("SPINDOWN\\..*\\.{}", channel_suffix(kind)),
      [table_call, &gate, &table](const Msg& m, const LcmMessage& r) {
        const std::int64_t now = r.recv_utime > 0 ? r.recv_utime : wall_us();
        if (const GateResult g = gate.check(r.channel, r.data, r.size, now); g.refused()) {
          const auto parsed = parse_channel(r.channel);
          table.on_refused(g, now, parsed && parsed->kind == ChannelKind::sample ? parsed->bench : std::string());
          return;
        }
        table_call(parse_channel(r.channel)->bench, m, now);
      },
      std::move(options));
}

// The suite's channels into the table (EXPLAIN is not shown); what does not decode, or makes
// the table throw, is one of the table's bad messages.
bool listen_to_lab(LcmLoop& loop, LabTable& table, const std::regex& wanted, MessageGate& gate) {
  loop.on_decode_error([&table](const LcmDecodeError& e) { table.on_bad_message(e.text(), e.recv_utime); });
  loop.on_handler_error([&table](const LcmMessage& m, const std::exception& e) {
    table.on_bad_message(fmt::format("{}: {}", m.channel, e.what()), m.recv_utime);
  });
  return listen<samples_t>(loop, ChannelKind::sample, wanted, false, gate, table,
                           [&table](const std::string& id, const samples_t& m, std::int64_t now) {
                             table.on_samples(id, m, now);
                           }) &&
         listen<config_t>(loop, ChannelKind::config, wanted, false, gate, table,
                          [&table](const std::string& id, const config_t& m, std::int64_t now) {
                            table.on_config(id, m, now);
                          }) &&
         listen<run_t>(loop, ChannelKind::run, wanted, false, gate, table,
                       [&table](const std::string& id, const run_t& m, std::int64_t now) { table.on_run(id, m, now); }) &&
         listen<fit_t>(loop, ChannelKind::fit, wanted, false, gate, table,
                       [&table](const std::string& id, const fit_t& m, std::int64_t now) { table.on_fit(id, m, now); }) &&
         // A bridge's heartbeat belongs to its bench (filtered); services are always shown.
         listen<status_t>(loop, ChannelKind::status, wanted, true, gate, table,
                          [&table, &wanted](const std::string& id, const status_t& m, std::int64_t now) {
                            if (m.service != "bridge" || std::regex_match(id, wanted)) table.on_status(id, m, now);
                          });
}

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
      "redrawn in place to the terminal's size: title, header and every bench row first (the run, the last fit's "
      "model, the combined model's c3 and c4 ± error, the health verdict), then the services and as many recent "
      "events as fit, each folded within the width; a narrow terminal shortens the cells, then drops BRIDGE, SEQ "
      "GAPS, RMSE, AGE and LAST FIT in that order. With --plain or when stdout is not a terminal, events (runs, fits, "
      "bridge changes, "
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
  add_lab_options(sub, opt->lab, "");
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
  LcmLoop loop(o.lcm_url);
  if (!loop.good()) {
    std::fprintf(stderr, "spindown watch: cannot start LCM%s%s\n", o.lcm_url.empty() ? "" : " at ",
                 o.lcm_url.c_str());
    return exit_unusable;
  }
  LabTableOptions topt;
  topt.lab_units = o.lab_units;
  MessageGate gate(gate_options_from(o.lab, o.lcm_url));
  topt.signatures_checked = gate.signing();
  LabTable table(topt);
  const std::regex wanted(o.bench_regex);
  if (!listen_to_lab(loop, table, wanted, gate)) {
    std::fprintf(stderr, "spindown watch: cannot subscribe to SPINDOWN\\..*\n");
    return exit_unusable;
  }
  StopSignals stop;

  const bool tty = ::isatty(STDOUT_FILENO) == 1;
  const bool redraw = tty && !o.plain && !o.once;
  const double duration = o.duration_s > 0 ? o.duration_s : (o.once ? 3.0 : 0.0);
  const double interval = o.interval_s > 0 ? o.interval_s : (redraw ? 1.0 : 10.0);
  std::deque<std::string> recent;  // events shown under a redrawn table (as many as fit)
  constexpr std::size_t recent_shown = 12;
  const auto redraw_screen = [&](std::int64_t t) {
    const std::vector<std::string> events(recent.begin(), recent.end());
    WatchScreenOptions size = terminal_size();
    size.max_events = recent_shown;
    print("\x1b[H\x1b[2J" + watch_screen(table, t, events, size));
  };

  if (!redraw && !o.once)
    print(fmt::format("spindown watch: listening{}{} (benches matching '{}'; lab '{}', {})\n",
                      o.lcm_url.empty() ? "" : " on ", o.lcm_url, o.bench_regex, gate.options().lab,
                      gate.signing() ? fmt::format("signatures checked with key {}", key_id_text(gate.options().key->id))
                                     : std::string("signatures not checked")));
  // After every wait: the table's events, as lines or under the redrawn table.
  loop.every(0, [&](std::int64_t t) {
    table.tick(t);
    for (auto& e : table.take_events()) {
      std::string line = clock_text(t) + "  " + e;
      if (redraw) {
        recent.push_back(std::move(line));
        if (recent.size() > recent_shown) recent.pop_front();
      } else if (!o.once && !o.no_events) {
        print(line + '\n');
      }
    }
  });
  // Every interval: the table redrawn, or (plain) printed when something changed.
  if (!o.once)
    loop.every(
        interval,
        [&](std::int64_t t) {
          if (redraw) {
            redraw_screen(t);
          } else if (table.changed()) {
            print('\n' + table.render(t) + '\n');
            table.clear_changed();
          }
        },
        redraw ? 0 : interval);
  if (loop.run({.stop = &stop, .timeout_s = duration}) == LcmLoopEnd::failed)
    std::fprintf(stderr, "spindown watch: LCM keeps failing to receive; stopping\n");
  loop.unsubscribe_all();

  // The last state stays on screen (a redraw) or closes the log (plain, --once).
  const std::int64_t t = wall_us();
  table.tick(t);
  if (redraw) {
    redraw_screen(t);
  } else {
    if (!o.once && !o.no_events)
      for (auto& e : table.take_events()) print(clock_text(t) + "  " + e + '\n');
    print((o.once ? "" : "\n") + table.render(t));
  }
  return exit_ok;
}

}  // namespace spindown::cli
