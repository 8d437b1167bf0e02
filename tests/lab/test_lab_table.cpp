// LabTable: the state and text behind `spindown watch`, fed decoded messages.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "lab_messages.hpp"
#include "spindown/lab_table.hpp"

namespace spindown {
namespace {

using test::fit_msg;

constexpr std::int64_t t0 = 1'700'000'000'000'000;  // µs since the epoch
constexpr std::int64_t sec = 1'000'000;

run_t run_msg(const std::string& bench, int run, std::int8_t state, double cut = 1.5, double stop = 9.25) {
  run_t m{};
  m.bench = bench;
  m.run = run;
  m.state = state;
  m.t_cut_s = cut;
  m.t_stop_s = stop;
  m.samples = 388;
  return m;
}

samples_t samples_msg(const std::string& bench, std::int64_t seq, int n) {
  samples_t m{};
  m.bench = bench;
  m.seq = seq;
  m.n = n;
  for (int i = 0; i < n; ++i) {
    m.device_time_us.push_back(20000 * (seq + i));
    m.host_time_us.push_back(t0);
    m.value.push_back(3.0);
    m.raw_adc.push_back(-1);
  }
  return m;
}

status_t status_msg(const std::string& service, const std::string& instance, const std::string& state,
                    std::vector<std::pair<std::string, std::int64_t>> counters,
                    std::vector<std::pair<std::string, double>> gauges = {}) {
  status_t s{};
  s.service = service;
  s.instance = instance;
  s.host = "labhost";
  s.pid = 42;
  s.state = state;
  for (auto& [k, v] : counters) {
    s.counter_name.push_back(k);
    s.counter_value.push_back(v);
  }
  s.ncounters = static_cast<std::int32_t>(s.counter_name.size());
  for (auto& [k, v] : gauges) {
    s.gauge_name.push_back(k);
    s.gauge_value.push_back(v);
  }
  s.ngauges = static_cast<std::int32_t>(s.gauge_name.size());
  return s;
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + '\n';
  return out;
}

TEST(LabTable, RunLifeBecomesStateAndEvents) {
  LabTable table;
  table.on_run("bench-a", run_msg("bench-a", 1, run_t::STATE_POWERED), t0);
  table.on_run("bench-a", run_msg("bench-a", 1, run_t::STATE_COASTING), t0 + sec);
  table.on_run("bench-a", run_msg("bench-a", 1, run_t::STATE_COASTING), t0 + sec);  // repeat: no event
  table.on_run("bench-a", run_msg("bench-a", 1, run_t::STATE_STOPPED), t0 + 2 * sec);
  const auto* row = table.bench("bench-a");
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(row->run, 1);
  EXPECT_EQ(row->run_state, static_cast<std::int8_t>(run_t::STATE_STOPPED));
  const auto events = table.take_events();
  ASSERT_EQ(events.size(), 3u) << joined(events);
  EXPECT_EQ(events[0], "bench-a: run 1 powered");
  EXPECT_EQ(events[1], "bench-a: run 1 coasting (cut at t = 1.50 s)");
  EXPECT_EQ(events[2], "bench-a: run 1 stopped (stop at t = 9.25 s, 7.75 s after the cut, 388 samples)");
  EXPECT_TRUE(table.take_events().empty());
  EXPECT_TRUE(contains(table.render(t0 + 2 * sec), "1 stopped"));
}

// A run the fitter joined mid-coast (it started, or took the bench in, after the cut) is
// partial in the table, the events and the fit's line: never shown as if its cut were seen.
TEST(LabTable, APartialRunIsSaidEverywhere) {
  LabTable table;
  run_t coasting = run_msg("bench-a", 1, run_t::STATE_COASTING);
  coasting.lead_in = "none";
  table.on_run("bench-a", coasting, t0);
  EXPECT_TRUE(contains(table.render(t0), "1 coasting (partial)")) << table.render(t0);
  run_t stopped = run_msg("bench-a", 1, run_t::STATE_STOPPED);
  stopped.lead_in = "none";
  table.on_run("bench-a", stopped, t0 + sec);
  fit_t f = fit_msg("bench-a", 1);
  f.lead_in = "none";
  table.on_fit("bench-a", f, t0 + sec);
  const auto events = table.take_events();
  ASSERT_EQ(events.size(), 3u) << joined(events);
  EXPECT_EQ(events[0], "bench-a: run 1 coasting (joined mid-coast at t = 1.50 s: the cut was not seen, a partial run)");
  EXPECT_TRUE(contains(events[1], "7.75 s after the first sample")) << events[1];
  EXPECT_TRUE(contains(events[2], "run 1 fit (partial: the cut was not seen")) << events[2];
  EXPECT_TRUE(contains(table.render(t0 + sec), "run 1 (partial) combined")) << table.render(t0 + sec);
}

TEST(LabTable, FitShowsBestModelCoefficientsAndRmse) {
  LabTable table;
  table.on_fit("bench-a", fit_msg("bench-a", 2), t0);
  const auto* row = table.bench("bench-a");
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(row->best, "combined");
  EXPECT_EQ(row->fit_run, 2);
  EXPECT_DOUBLE_EQ(row->rmse, 0.0123);
  // Only the best model's friction coefficients, not ω0 or curve constants, nor other models'.
  EXPECT_TRUE(contains(row->coefficients, "c3 = ")) << row->coefficients;
  EXPECT_TRUE(contains(row->coefficients, "c4 = ")) << row->coefficients;
  EXPECT_FALSE(contains(row->coefficients, "c1")) << row->coefficients;
  EXPECT_FALSE(contains(row->coefficients, "omega0")) << row->coefficients;
  EXPECT_TRUE(contains(row->coefficients, "±")) << row->coefficients;
  EXPECT_FALSE(contains(row->coefficients, "N·m")) << row->coefficients;  // units: once, under the table
  const std::string text = table.render(t0);
  // The combined model's c3 and c4 in columns of their own, scaled by a power of ten said once.
  for (const char* cell : {"run 2 combined ", " 1.822±0.011 ", " 1.1390±0.0020 ", " 0.0123 V "})
    EXPECT_TRUE(contains(text, cell)) << cell << "\n" << text;
  EXPECT_TRUE(contains(text, "c3 (1e-7 N·m·s/rad)")) << text;
  EXPECT_TRUE(contains(text, "c3 in 1e-7 N·m·s/rad, c4 in 1e-4 N·m (combined model, ± total error)"))
      << text;
  const auto events = table.take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_TRUE(contains(events[0], "bench-a: run 2 fit: best combined: c3 = (1.822 ± 0.011)e-07 N·m·s/rad, c4 = "))
      << events[0];
  EXPECT_TRUE(contains(events[0], "RMSE 0.0123 V")) << events[0];
}

TEST(LabTable, TheTotalErrorWhenJAndKbAreUncertain) {
  fit_t m = fit_msg("b", 1);
  m.param_bench_error.assign(m.param_stderr.size(), 0.0);
  for (std::size_t k = 0; k < m.param_name.size(); ++k)
    if (m.param_name[k] == "c3") m.param_bench_error[k] = 0.02 * m.param_value[k];  // J known to 2 %
  // c3's statistical 1.1e-9 and J's 3.644e-9 (2 %): √(1.1² + 3.644²) = 3.8e-9.
  EXPECT_EQ(fit_coefficients_text(m, false, false).rfind("c3 = (1.822 ± 0.038)e-07,", 0), 0u)
      << fit_coefficients_text(m, false, false);
}

TEST(LabTable, LabUnitsMatchTheLabReport) {
  const std::string text = fit_coefficients_text(fit_msg("b", 1), true);
  EXPECT_EQ(text, "c3 = 1.822 ± 0.011 g·cm²·s⁻¹, c4 = 1139.0 ± 2.0 g·cm²·rad·s⁻²");
  EXPECT_EQ(fit_coefficients_text(fit_msg("b", 1), true, false), "c3 = 1.822 ± 0.011, c4 = 1139.0 ± 2.0");
  LabTableOptions opt;
  opt.lab_units = true;
  LabTable table(opt);
  table.on_fit("b", fit_msg("b", 1), t0);
  const std::string page = table.render(t0);
  EXPECT_TRUE(contains(page, "c3 in g·cm²·s⁻¹, c4 in g·cm²·rad·s⁻²")) << page;
  EXPECT_TRUE(contains(page, " 1.822±0.011 ") && contains(page, " 1139.0±2.0 ")) << page;  // the lab's units, unscaled
}

TEST(LabTable, FitWithoutBestModelSaysSo) {
  LabTable table;
  fit_t m = fit_msg("b", 3, "");
  m.bench_source = "default (no CONFIG yet)";
  table.on_fit("b", m, t0);
  EXPECT_TRUE(contains(table.render(t0), "run 3: no model converged"));
  const auto events = table.take_events();
  ASSERT_EQ(events.size(), 1u);
  EXPECT_TRUE(contains(events[0], "no model converged")) << events[0];
  EXPECT_TRUE(contains(events[0], "[J/K_b: default (no CONFIG yet)]")) << events[0];
  // A best name that is not among the models gives no coefficients rather than wrong ones.
  EXPECT_EQ(fit_coefficients_text(fit_msg("b", 1, "stribeck"), false), "");
}

TEST(LabTable, SequenceGapsRepeatsAndRestarts) {
  LabTableOptions opt;
  opt.gap_event_every_s = 10;
  LabTable table(opt);
  table.on_samples("b", samples_msg("b", 0, 5), t0);
  table.on_samples("b", samples_msg("b", 5, 5), t0);
  table.on_samples("b", samples_msg("b", 12, 3), t0 + sec);    // 10, 11 lost
  table.on_samples("b", samples_msg("b", 12, 3), t0 + sec);    // repeated message: ignored
  table.on_samples("b", samples_msg("b", 20, 1), t0 + 2 * sec);  // 15..19 lost
  const auto* row = table.bench("b");
  ASSERT_NE(row, nullptr);
  // A gap may still fill with late datagrams (the reorder window): nothing is lost yet.
  EXPECT_EQ(row->seq_gaps, 0);
  EXPECT_EQ(row->samples, 10);
  EXPECT_TRUE(table.take_events().empty());
  table.tick(t0 + 4 * sec);
  EXPECT_EQ(row->seq_gaps, 2);
  EXPECT_EQ(row->samples_missing, 7);
  EXPECT_EQ(row->samples, 14);
  EXPECT_EQ(row->sample_messages, 4);
  EXPECT_TRUE(contains(table.render(t0 + 4 * sec), "2 (7 lost)"));
  // One gap event, then none until gap_event_every_s has passed.
  auto events = table.take_events();
  ASSERT_EQ(events.size(), 1u) << joined(events);
  EXPECT_TRUE(contains(events[0], "sequence gaps: 2 so far, 7 samples lost")) << events[0];
  table.on_samples("b", samples_msg("b", 30, 1), t0 + 12 * sec);  // 21..29 lost
  EXPECT_TRUE(table.take_events().empty());
  table.tick(t0 + 14 * sec + 1);
  events = table.take_events();
  ASSERT_EQ(events.size(), 1u) << joined(events);
  EXPECT_TRUE(contains(events[0], "sequence gaps: 3 so far, 16 samples lost")) << events[0];
  // A restarted bridge (a new session) numbers from 0 again: a new stream, not a gap, not repeated.
  auto restarted = samples_msg("b", 0, 4);
  restarted.source_session = 2;
  table.on_samples("b", restarted, t0 + 14 * sec);
  EXPECT_EQ(table.bench("b")->seq_restarts, 1);
  EXPECT_EQ(table.bench("b")->seq_gaps, 3);
  restarted = samples_msg("b", 4, 4);
  restarted.source_session = 2;
  table.on_samples("b", restarted, t0 + 14 * sec);
  EXPECT_EQ(table.bench("b")->seq_gaps, 3);
  EXPECT_EQ(table.bench("b")->samples, 23);
  events = table.take_events();
  ASSERT_FALSE(events.empty());
  EXPECT_TRUE(contains(events[0], "b: a new source: host ? (session 0000000000000002)")) << events[0];
}

// A second source on a bench's channel at the same time is named in an event, in the row and
// under the table while it lasts; its samples are not counted as the bench's.
TEST(LabTable, TwoSourcesOnABenchAreShown) {
  LabTable table;
  for (int i = 0; i < 20; ++i) {
    auto a = samples_msg("b", i, 1);
    a.source_session = 1;
    a.source_host = "pc-a";
    table.on_samples("b", a, t0 + i * 20000);
    auto b = samples_msg("b", 1000 + i, 1);
    b.source_session = 2;
    b.source_host = "laptop";
    table.on_samples("b", b, t0 + i * 20000 + 5000);
  }
  const auto* row = table.bench("b");
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(row->samples, 20);
  EXPECT_GT(row->other_source_samples, 10);
  const std::string shown = table.render(t0 + sec);
  EXPECT_TRUE(contains(shown, "TWO SOURCES")) << shown;
  EXPECT_TRUE(contains(shown, "SPINDOWN.b.SAMPLE has two sources: host pc-a (session 0000000000000001) and host "
                              "laptop (session 0000000000000002)"))
      << shown;
  EXPECT_FALSE(contains(table.render(t0 + 30 * sec), "TWO SOURCES"));  // gone quiet: no longer shown
}

// Two fitters with one instance name: one row that says so, an event naming both; a FIT from a
// session no fitter heard on STATUS is marked NOT VERIFIED; refused messages are counted, not shown.
TEST(LabTable, CollidingFittersUnknownFitsAndRefusedMessages) {
  LabTable table;
  auto f1 = status_msg("fitter", "fitter", "running", {{"fits", 1}});
  f1.source_session = 11;
  f1.source_host = "pc-a";
  f1.pid = 100;
  auto f2 = f1;
  f2.source_session = 12;
  f2.source_host = "pc-b";
  f2.pid = 200;
  table.on_status("fitter", f1, t0);
  table.on_status("fitter", f2, t0 + 100000);
  const auto events = table.take_events();
  EXPECT_TRUE(std::any_of(events.begin(), events.end(), [](const std::string& e) {
    return contains(e, "two fitters with the same instance name 'fitter' on this lab at once") && contains(e, "pid 100") &&
           contains(e, "pid 200");
  })) << joined(events);
  EXPECT_TRUE(contains(table.render(t0 + sec), "2 INSTANCES!")) << table.render(t0 + sec);
  auto fit = fit_msg("b", 1, "combined");
  fit.source_session = 99;
  fit.source_host = "laptop";
  table.on_fit("b", fit, t0 + sec);
  EXPECT_FALSE(table.bench("b")->fit_doubt.empty());
  EXPECT_TRUE(contains(table.render(t0 + sec), "NOT VERIFIED")) << table.render(t0 + sec);
  fit.source_session = 11;  // a fitter heard on STATUS
  table.on_fit("b", fit, t0 + sec);
  EXPECT_TRUE(table.bench("b")->fit_doubt.empty());
  GateResult refused;
  refused.verdict = GateVerdict::not_signed;
  refused.text = "SPINDOWN.b.FIT: fit_t from host laptop (session 0000000000000063): not signed; not used";
  table.on_refused(refused, t0 + sec);
  table.on_refused(refused, t0 + sec);
  EXPECT_EQ(table.refused_messages(), 2);
  EXPECT_TRUE(contains(table.render(t0 + sec), "2 messages not shown (2 not signed); last: SPINDOWN.b.FIT"))
      << table.render(t0 + sec);
}

// A bench whose samples are all refused (its PC has another key) has a row that says so, and why;
// another lab's bench of a name never gets one; a bench whose samples are let through again is
// back to its run (issue 42).
TEST(LabTable, ABenchWhoseSamplesAreRefusedIsShownRefused) {
  LabTable table;
  GateResult rekeyed;
  rekeyed.verdict = GateVerdict::other_key;
  rekeyed.text = "SPINDOWN.b9.SAMPLE: samples_t from host pc9 (session 0000000000000009): signed with key 0x1, not "
                 "this lab's key 0x2; not used";
  table.on_refused(rekeyed, t0, "b9");
  GateResult other_lab;
  other_lab.verdict = GateVerdict::other_lab;
  other_lab.text = "SPINDOWN.b8.SAMPLE: samples_t …: a message of lab 'B'; not used";
  table.on_refused(other_lab, t0, "b8");
  EXPECT_EQ(table.bench("b8"), nullptr);
  const std::string text = table.render(t0 + sec);
  EXPECT_TRUE(contains(text, "REFUSED: other key")) << text;
  EXPECT_TRUE(contains(text, "b9: its samples are refused: SPINDOWN.b9.SAMPLE")) << text;
  table.on_samples("b9", samples_msg("b9", 0, 5), t0 + 2 * sec);
  EXPECT_FALSE(contains(table.render(t0 + 2 * sec), "REFUSED")) << table.render(t0 + 2 * sec);
  EXPECT_FALSE(contains(table.render(t0 + 20 * sec), "REFUSED"));
}

TEST(LabTable, BridgeStatusGoesToItsBenchServicesToTheirOwnRows) {
  LabTable table;
  table.on_status("bench-a",
                  status_msg("bridge", "bench-a", "connected", {{"lines_good", 1520}, {"lines_bad", 3}},
                             {{"connected", 1}, {"rate_hz", 50}}),
                  t0);
  table.on_status("fitter",
                  status_msg("fitter", "fitter", "running",
                             {{"messages", 99}, {"samples", 4500}, {"fits", 6}, {"seq_gaps", 2}, {"queue_drops", 0}}),
                  t0);
  table.on_status("logger", status_msg("logger", "logger", "running", {{"events", 9000}, {"drops", 0}}), t0);
  EXPECT_EQ(table.bench_count(), 1u);  // "fitter" and "logger" are not benches
  EXPECT_EQ(table.service_count(), 2u);
  const auto* row = table.bench("bench-a");
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(row->bridge_state, "connected");
  EXPECT_EQ(row->lines_good, 1520);
  EXPECT_EQ(row->lines_bad, 3);
  EXPECT_DOUBLE_EQ(row->rate_hz, 50);
  const auto* fitter = table.service("fitter", "fitter");
  ASSERT_NE(fitter, nullptr);
  ASSERT_EQ(fitter->counters.size(), 3u);  // samples, fits, seq_gaps: in the table's order
  EXPECT_EQ(fitter->counters[0].first, "samples");
  EXPECT_EQ(fitter->counters[2].second, 2);
  const std::string text = table.render(t0);
  EXPECT_TRUE(contains(text, "connected 1520/3 50 Hz")) << text;
  EXPECT_TRUE(contains(text, "samples 4500, fits 6, seq_gaps 2")) << text;
  EXPECT_TRUE(contains(text, "events 9000, drops 0")) << text;

  // A disconnect and the bridge's error become events.
  table.take_events();
  status_t down = status_msg("bridge", "bench-a", "disconnected", {{"lines_good", 1520}});
  down.last_error = "cannot open /dev/ttyACM0: No such file or directory";
  table.on_status("bench-a", down, t0 + sec);
  const auto events = table.take_events();
  EXPECT_TRUE(contains(joined(events), "bench-a: bridge disconnected")) << joined(events);
  EXPECT_TRUE(contains(joined(events), "cannot open /dev/ttyACM0")) << joined(events);
}

TEST(LabTable, AgeAndStaleMark) {
  LabTableOptions opt;
  opt.stale_s = 5;
  LabTable table(opt);
  table.on_run("b", run_msg("b", 1, run_t::STATE_COASTING), t0);
  EXPECT_TRUE(contains(table.render(t0 + 2 * sec), "  2.0 s  ")) << table.render(t0 + 2 * sec);
  EXPECT_TRUE(contains(table.render(t0 + 7 * sec), "  7.0 s !  ")) << table.render(t0 + 7 * sec);
}

// A run shown coasting whose fitter stopped heartbeating (killed, host gone) is no longer shown
// as coasting for ever: after fitter_lost_s it says nobody follows it; a fitter still beating
// keeps it coasting, and a fitter whose last word was "stopping" lets it go at once.
TEST(LabTable, ARunNoFitterFollowsAnyMoreAgesOut) {
  LabTableOptions opt;
  opt.fitter_lost_s = 10;
  {
    LabTable table(opt);
    table.on_status("fitter", status_msg("fitter", "fitter", "running", {}), t0);
    table.on_run("b", run_msg("b", 1, run_t::STATE_COASTING), t0);
    EXPECT_TRUE(contains(table.render(t0 + 5 * sec), "1 coasting  ")) << table.render(t0 + 5 * sec);
    const std::string later = table.render(t0 + 12 * sec);
    EXPECT_TRUE(contains(later, "1 not followed (no fitter for 12 s)")) << later;
  }
  {
    LabTable table(opt);
    table.on_run("b", run_msg("b", 1, run_t::STATE_COASTING), t0);
    for (int i = 1; i <= 60; ++i) table.on_status("fitter", status_msg("fitter", "fitter", "running", {}), t0 + i * sec);
    const std::string text = table.render(t0 + 60 * sec);
    EXPECT_TRUE(contains(text, "1 coasting  ")) << "a long coast, its fitter alive: " << text;
    table.on_status("fitter", status_msg("fitter", "fitter", "stopping", {}), t0 + 61 * sec);
    EXPECT_TRUE(contains(table.render(t0 + 61 * sec), "1 not followed (no fitter for 61 s)")) << table.render(t0 + 61 * sec);
  }
}

TEST(LabTable, BoundedRowsAndEvents) {
  LabTableOptions opt;
  opt.max_benches = 3;
  opt.max_events = 4;
  LabTable table(opt);
  for (int i = 0; i < 5; ++i) table.on_run("b" + std::to_string(i), run_msg("b", 1, run_t::STATE_COASTING), t0 + i);
  EXPECT_EQ(table.bench_count(), 3u);
  EXPECT_EQ(table.forgotten_rows(), 2);
  EXPECT_EQ(table.bench("b0"), nullptr);  // the least recently heard went first
  EXPECT_NE(table.bench("b4"), nullptr);
  EXPECT_EQ(table.take_events().size(), 4u);
  EXPECT_GT(table.dropped_events(), 0);
}

TEST(LabTable, BadMessagesCountedAndShown) {
  LabTable table;
  table.on_bad_message("SPINDOWN.x.FIT: 7 bytes that do not decode as fit_t", t0);
  table.on_bad_message("SPINDOWN.x.FIT: 9 bytes that do not decode as fit_t", t0);
  EXPECT_EQ(table.bad_messages(), 2);
  EXPECT_TRUE(contains(table.render(t0), "2 undecodable messages; last: SPINDOWN.x.FIT: 9 bytes"));
  EXPECT_EQ(table.take_events().size(), 1u);  // only the first becomes an event
}

TEST(LabTable, WidthCutsEveryLineAndColumnsAlign) {
  LabTable table;
  table.on_fit("bench-a", fit_msg("bench-a", 2), t0);
  table.on_fit("b", fit_msg("b", 1, ""), t0);
  const std::string full = table.render(t0);
  std::istringstream lines(full);
  std::string line, header, first, second;
  std::getline(lines, line);  // title
  std::getline(lines, header);
  std::getline(lines, first);
  std::getline(lines, second);
  // Columns line up in code points, whatever bytes "±" and "·" take: row "b" (sorted first) has
  // no RMSE, its "-" sits under the header's RMSE, as bench-a's value does.
  // The code points of line from column col on (n of them).
  const auto at_column = [](const std::string& line, std::size_t col, std::size_t n) {
    const std::size_t from = utf8_prefix_bytes(line, col);
    return line.substr(from, utf8_prefix_bytes(std::string_view(line).substr(from), n));
  };
  const auto rmse_byte = header.find("RMSE");
  ASSERT_NE(rmse_byte, std::string::npos);
  const std::size_t rmse_col = display_width(header.substr(0, rmse_byte));
  EXPECT_EQ(at_column(first, rmse_col, 2), "- ") << full;
  EXPECT_EQ(at_column(second, rmse_col, 8), "0.0123 V") << full;
  EXPECT_TRUE(second.starts_with("bench-a")) << full;
  const std::string cut = table.render(t0, 40);
  std::istringstream cut_lines(cut);
  while (std::getline(cut_lines, line)) EXPECT_LE(display_width(line), 40u) << line;
  EXPECT_EQ(display_width("c3 = 1 ± 2 g·cm²"), 16u);
}

TEST(LabTable, ChangedFlagFollowsInput) {
  LabTable table;
  EXPECT_FALSE(table.changed());
  table.on_config("b", config_t{}, t0);
  EXPECT_TRUE(table.changed());
  table.clear_changed();
  EXPECT_FALSE(table.changed());
  EXPECT_FALSE(contains(table.render(t0), "(no bench heard yet)"));
  EXPECT_TRUE(contains(LabTable().render(t0), "(no bench heard yet)"));
}

}  // namespace
// An 80-column terminal: short headers and cells, then the columns worth least dropped in their
// order, so that the run, c3 and c4 with their errors and the verdict always fit; at 120 columns
// nothing is dropped or cut.
TEST(LabTable, UsableInEightyColumns) {
  LabTable table;
  for (const char* id : {"teaching-lab-bench-000", "teaching-lab-bench-001", "teaching-lab-bench-002"}) {
    table.on_status(id, status_msg("bridge", id, "connected", {{"lines_good", 15200}, {"lines_bad", 3}}, {{"rate_hz", 49.6}}), t0);
    table.on_samples(id, samples_msg(id, 0, 10), t0);
    table.on_run(id, run_msg(id, 12, run_t::STATE_COASTING), t0);
    fit_t m = fit_msg(id, 11);
    m.verdict = "not_judged";
    table.on_fit(id, m, t0);
  }
  for (std::size_t width : {80u, 120u}) {
    const std::string text = table.render(t0, width);
    std::istringstream lines(text);
    std::string line, header;
    std::vector<std::string> rows;
    while (std::getline(lines, line)) {
      EXPECT_LE(display_width(line), width) << line;
      if (line.starts_with("BENCH")) header = line;
      if (line.starts_with("teaching-lab-bench-")) rows.push_back(line);
    }
    ASSERT_EQ(rows.size(), 3u) << text;
    for (const auto& row : rows) {
      EXPECT_TRUE(contains(row, "12 coast")) << text;
      EXPECT_TRUE(contains(row, "1.822±0.011  1.1390±0.0020")) << text;
      EXPECT_TRUE(row.ends_with("NOT JUDGED")) << text;
    }
    EXPECT_TRUE(contains(header, "c3") && contains(header, "c4") && contains(header, "HEALTH")) << text;
    if (width == 80) {
      EXPECT_FALSE(contains(header, "BRIDGE")) << text;  // the first to go
      EXPECT_TRUE(contains(text, "not shown at this width: BRIDGE")) << text;
    } else {
      for (const char* column : {"BRIDGE", "GAPS", "AGE", "FIT", "RMSE"}) EXPECT_TRUE(contains(header, column)) << text;
      EXPECT_FALSE(contains(text, "not shown")) << text;
      EXPECT_TRUE(contains(rows[0], "50 Hz, 3 bad")) << text;
    }
  }
}

}  // namespace spindown

