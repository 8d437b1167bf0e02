// WebLab: what spindown-web's pages show, fed one simulated run of the lab's bench as the bridge
// and the fitter publish it. The truths: the coefficients on the page are the FIT message's own
// numbers; the page's curves are the models the fit found (they run through the data within its
// noise); the run's CSV holds every sample the bridge sent; memory and points stay bounded.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "spindown/fit_view.hpp"
#include "spindown/web_lab.hpp"
#include "web_test_support.hpp"

namespace spindown {
namespace {

using namespace spindown::test;

// The data of every event of a given name among the updates, for clients of bench ("" = room).
std::vector<Json> events(const std::vector<WebUpdate>& updates, const std::string& name, const std::string& bench) {
  std::vector<Json> out;
  for (const auto& u : updates) {
    const bool for_it = u.to == WebUpdate::To::everyone || (bench.empty() && (u.to == WebUpdate::To::room || u.to == WebUpdate::To::room_and_bench)) ||
                        (!bench.empty() && (u.to == WebUpdate::To::bench || u.to == WebUpdate::To::room_and_bench) && u.bench == bench);
    if (!for_it) continue;
    const std::string& e = *u.event;
    if (e.rfind("event: " + name + "\n", 0) != 0) continue;
    const auto data = e.find("data: ");
    out.push_back(Json::parse(e.substr(data + 6)));
  }
  return out;
}

const Json& bench_of(const Json& state, const std::string& id) {
  for (const auto& b : state["benches"])
    if (b["id"] == id) return b;
  throw std::runtime_error("no bench " + id);
}

TEST(WebLab, TheFitOnThePageIsTheFitMessagesOwnNumbers) {
  const SimulatedRun r = simulated_run();
  WebLab lab;
  const std::int64_t now = feed_run(lab, r);
  const Json state = lab.state_json(now);
  const Json& b = bench_of(state, "b1");
  const Json& fit = b["last_fit"];
  ASSERT_FALSE(fit.is_null());
  EXPECT_EQ(fit["run"], 1);
  EXPECT_EQ(fit["best"], r.fit.best);
  // Exactly the message's doubles, through JSON text and back.
  const Json back = Json::parse(state.dump());
  const Json& f2 = bench_of(back, "b1")["last_fit"];
  EXPECT_EQ(f2["c3"]["value"].get<double>(), fit_param(r.fit, "combined", "c3"));
  EXPECT_EQ(f2["c4"]["value"].get<double>(), fit_param(r.fit, "combined", "c4"));
  EXPECT_EQ(f2["c1"]["value"].get<double>(), fit_param(r.fit, "viscous", "c1"));
  // And near the simulator's truth (c3 = 1.822e-7, c4 = 1.1389e-4) within a few errors.
  EXPECT_NEAR(f2["c4"]["value"].get<double>(), 1.1389e-4, 5 * f2["c4"]["stderr"].get<double>());
  EXPECT_NEAR(f2["c3"]["value"].get<double>(), 1.822e-7, 5 * f2["c3"]["stderr"].get<double>());
  // The text is in the lab's units with its ± error: c4 ≈ 1139 g·cm²·rad·s⁻².
  const std::string c4_text = f2["c4"]["text"];
  EXPECT_NE(c4_text.find("±"), std::string::npos) << c4_text;
  EXPECT_NE(c4_text.find("g·cm²·rad·s⁻²"), std::string::npos) << c4_text;
  EXPECT_NEAR(std::stod(c4_text), f2["c4"]["value"].get<double>() * 1e7, 0.01 * 1139) << c4_text;
  // Both texts, for the page's units toggle: the lab's (g·cm²…) and SI's, the same number.
  const std::string c4_lab = f2["c4"]["text_lab"], c4_si = f2["c4"]["text_si"];
  EXPECT_EQ(c4_lab, c4_text);
  EXPECT_NE(c4_si.find("N·m"), std::string::npos) << c4_si;
  EXPECT_EQ(c4_si.find("g·cm"), std::string::npos) << c4_si;
  EXPECT_NEAR(std::stod(c4_si.substr(c4_si.find_first_of("0123456789"))), f2["c4"]["value"].get<double>() * 1e4, 0.01 * 1.139)
      << c4_si;
  EXPECT_EQ(f2["health"], "not judged");  // no bench file: never "ok"
  // What the printed lab record needs: J and K_b the fit used, where they came from, and when.
  EXPECT_EQ(f2["inertia_kg_m2"].get<double>(), r.fit.inertia_kg_m2);
  EXPECT_EQ(f2["kb_v_s_per_rad"].get<double>(), r.fit.kb_v_s_per_rad);
  EXPECT_EQ(f2["inertia_source"], r.fit.inertia_source);
  EXPECT_EQ(f2["kb_source"], r.fit.kb_source);
  EXPECT_EQ(f2["unix_ms"].get<std::int64_t>(), r.fit.utime / 1000);
}

TEST(WebLab, TheLabsNameIsOnEveryPage) {
  WebLabOptions o;
  o.lab_name = "phys-2b";
  WebLab lab(o);
  EXPECT_EQ(lab.state_json(1)["lab"]["name"], "phys-2b");
}

TEST(WebLab, TheModelsCurvesRunThroughTheReadingsWithinTheirNoise) {
  const SimulatedRun r = simulated_run(11);
  WebLab lab;
  const std::int64_t now = feed_run(lab, r);
  const auto j = lab.bench_json("b1", now);
  ASSERT_TRUE(j);
  const Json& run = (*j)["detail"]["run"];
  ASSERT_FALSE(run["curves"].is_null());
  ASSERT_EQ(run["curves"]["models"].size(), 3u);
  for (const auto& m : run["curves"]["models"]) {
    EXPECT_TRUE(m["converged"].get<bool>()) << m["name"];
    EXPECT_GE(m["curve"].size(), 100u);
  }
  // The best model's residuals: every sample of the fitted window, mean ~0, RMS = the FIT's RMSE.
  const Json& res = run["curves"]["residuals"];
  ASSERT_FALSE(res.is_null());
  double sum = 0, sum2 = 0;
  for (const auto& p : res["points"]) {
    sum += p[1].get<double>();
    sum2 += p[1].get<double>() * p[1].get<double>();
  }
  const double n = static_cast<double>(res["points"].size());
  ASSERT_GT(n, 500);
  const double rmse = (*j)["bench"]["last_fit"]["rmse"];
  EXPECT_NEAR(std::sqrt(sum2 / n), rmse, 0.05 * rmse);
  EXPECT_LT(std::fabs(sum / n), 0.2 * rmse);
  // The best curve at τ = 0 reads what the bench read just after the cut (the back-EMF, ~2.8 V).
  for (const auto& m : run["curves"]["models"])
    if (m["name"] == (*j)["bench"]["last_fit"]["best"]) {
      EXPECT_NEAR(m["curve"][0][1].get<double>(), 2.8, 0.05);
    }
  // The markers: the cut at 0 (the plot's zero), the stop at the stop's time after it.
  EXPECT_DOUBLE_EQ(run["markers"]["cut"].get<double>(), 0.0);
  EXPECT_NEAR(run["markers"]["stop"].get<double>(), r.t_stop_s - r.t_cut_s, 1e-9);
}

TEST(WebLab, ARunGainsPointsWhileItCoastsAndItsCsvHoldsEverySample) {
  const SimulatedRun r = simulated_run(3);
  WebLab lab;
  std::int64_t last_n = -1, grew = 0, now = t0_us;
  bool coasting_seen = false;
  std::size_t first_in_run = r.t_us.size();
  for (std::size_t i = 0; i < r.t_us.size(); ++i) {
    now = t0_us + static_cast<std::int64_t>(i) * 20000;
    lab.on_samples("b1", one_sample("b1", static_cast<std::int64_t>(i), r.t_us[i], r.v[i]), now);
    const double t = static_cast<double>(r.t_us[i]) / 1e6;
    if (first_in_run == r.t_us.size() && t > r.t_cut_s + 0.1) {
      lab.on_run("b1", run_message("b1", 1, run_t::STATE_COASTING, r.t_cut_s, std::nan("")), now);
      first_in_run = 0;
      while (static_cast<double>(r.t_us[first_in_run]) / 1e6 < r.t_cut_s - 2.0) ++first_in_run;
    }
    if (i % 10 == 0) {
      for (const Json& s : events(lab.take_updates(now), "samples", "b1")) {
        const std::int64_t n = s["benches"]["b1"]["n"];
        if (last_n >= 0 && n > last_n) ++grew;
        last_n = n;
      }
      const Json st = lab.state_json(now);
      if (bench_of(st, "b1")["state"] == "coasting") coasting_seen = true;
    }
  }
  EXPECT_TRUE(coasting_seen);
  EXPECT_GT(grew, 50);
  fit_t fit = r.fit;
  lab.on_fit("b1", fit, now);
  // The CSV: a header, then every sample from 2 s before the cut to the FIT, exactly.
  const auto csv = lab.run_csv("b1", 1);
  ASSERT_TRUE(csv);
  std::istringstream in(*csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "t_s,value");
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    const std::size_t k = first_in_run + rows;
    ASSERT_LT(k, r.t_us.size());
    const auto comma = line.find(',');
    EXPECT_EQ(std::stod(line.substr(0, comma)), static_cast<double>(r.t_us[k]) / 1e6) << line;
    EXPECT_EQ(std::stod(line.substr(comma + 1)), r.v[k]) << line;
    ++rows;
  }
  EXPECT_EQ(first_in_run + rows, r.t_us.size());
  EXPECT_EQ(bench_of(lab.state_json(now), "b1")["run"]["samples"].get<std::size_t>(), rows);
  EXPECT_FALSE(lab.run_csv("b1", 2));
  EXPECT_FALSE(lab.run_csv("nobody", 1));
}

TEST(WebLab, AFitArrivesAsOneDetailEventWithCurvesAndTheRoomsTile) {
  const SimulatedRun r = simulated_run(5);
  WebLab lab;
  feed_run(lab, r);  // everything up to the FIT
  const auto updates = lab.take_updates(t0_us + 100 * sec_us);
  const auto details = events(updates, "detail", "b1");
  ASSERT_EQ(details.size(), 1u);
  EXPECT_EQ(details[0]["run"]["fit"]["c3"]["value"].get<double>(), fit_param(r.fit, "combined", "c3"));
  EXPECT_EQ(details[0]["run"]["curves"]["models"].size(), 3u);
  EXPECT_TRUE(events(updates, "detail", "").empty());  // the room gets the tile, not the curves
  const auto tiles = events(updates, "bench", "");
  ASSERT_EQ(tiles.size(), 1u);
  EXPECT_EQ(tiles[0]["last_fit"]["c4"]["value"].get<double>(), fit_param(r.fit, "combined", "c4"));
  // Nothing changed: nothing more is sent.
  EXPECT_TRUE(events(lab.take_updates(t0_us + 100 * sec_us), "detail", "b1").empty());
}

TEST(WebLab, ALongRunIsThinnedForThePagesButCountedWhole) {
  WebLabOptions o;
  o.max_display_points = 500;
  o.max_run_samples = 3000;
  WebLab lab(o);
  lab.on_run("b1", run_message("b1", 1, run_t::STATE_COASTING, 0.0, std::nan("")), t0_us);
  for (int i = 0; i < 5000; ++i)
    lab.on_samples("b1", one_sample("b1", i, 1000 + 20000 * std::int64_t(i), 2.0), t0_us + i * 20000);
  const auto j = lab.bench_json("b1", t0_us + 5000 * 20000);
  ASSERT_TRUE(j);
  EXPECT_LE((*j)["samples"]["p"].size(), 500u);
  EXPECT_GT((*j)["samples"]["p"].size(), 250u);
  EXPECT_EQ((*j)["samples"]["n"], 5000);
  EXPECT_TRUE((*j)["bench"]["run"]["truncated"].get<bool>());
  const auto csv = lab.run_csv("b1", 1);
  ASSERT_TRUE(csv);
  EXPECT_EQ(std::count(csv->begin(), csv->end(), '\n'), 3001);  // header + max_run_samples rows
}

TEST(WebLab, StatesFollowTheRunAndTheBenchGoesSilent) {
  WebLabOptions o;
  o.silent_after_s = 3;
  WebLab lab(o);
  const auto state = [&](std::int64_t now) { return bench_of(lab.state_json(now), "b1")["state"].get<std::string>(); };
  lab.on_samples("b1", one_sample("b1", 0, 1000, 0.0), t0_us);
  EXPECT_EQ(state(t0_us), "idle");
  lab.on_samples("b1", one_sample("b1", 1, 21000, 3.1), t0_us + 20000);  // supply on the pin
  EXPECT_EQ(state(t0_us + 20000), "powered");
  lab.on_run("b1", run_message("b1", 1, run_t::STATE_COASTING, 0.03, std::nan("")), t0_us + 40000);
  EXPECT_EQ(state(t0_us + 40000), "coasting");
  lab.on_samples("b1", one_sample("b1", 2, 41000, 0.0), t0_us + 60000);
  lab.on_run("b1", run_message("b1", 1, run_t::STATE_STOPPED, 0.03, 0.04), t0_us + 60000);
  EXPECT_EQ(state(t0_us + 60000), "stopped");
  EXPECT_EQ(state(t0_us + 60000 + 4 * sec_us), "silent");
  // A run whose cut was not seen.
  lab.on_samples("b1", one_sample("b1", 3, 61000, 2.0), t0_us + 5 * sec_us);
  lab.on_run("b1", run_message("b1", 2, run_t::STATE_COASTING, 0.061, std::nan(""), "none"), t0_us + 5 * sec_us);
  EXPECT_EQ(state(t0_us + 5 * sec_us), "partial");
  // A bench file's bench that was never heard.
  WebLabOptions e;
  e.expected_benches = {"b9"};
  WebLab expected(e);
  EXPECT_EQ(bench_of(expected.state_json(t0_us), "b9")["state"], "silent");
  EXPECT_EQ(bench_of(expected.state_json(t0_us), "b9")["bridge"]["health"], "silent");
}

// A bench whose every sample the gate refuses (its PC has another key) gets a tile that says it is
// refused, and why; another lab's bench of a name gets none (issue 42).
TEST(WebLab, ABenchWhoseSamplesAreRefusedHasATileThatSaysSo) {
  WebLab lab;
  GateResult rekeyed;
  rekeyed.verdict = GateVerdict::other_key;
  rekeyed.text = "SPINDOWN.b7.SAMPLE: samples_t from host pc7 (session 07): signed with key 0x1, not this lab's key 0x2";
  lab.on_refused(rekeyed, t0_us, "b7");
  GateResult other_lab;
  other_lab.verdict = GateVerdict::other_lab;
  other_lab.text = "SPINDOWN.b6.SAMPLE: a message of lab 'B'";
  lab.on_refused(other_lab, t0_us, "b6");
  const Json st = lab.state_json(t0_us + sec_us);
  EXPECT_EQ(bench_of(st, "b7")["state"], "refused");
  EXPECT_NE(bench_of(st, "b7")["refused"].get<std::string>().find("signed with key 0x1"), std::string::npos);
  for (const Json& b : st["benches"]) EXPECT_NE(b["id"], "b6");
}

TEST(WebLab, TheBridgesHealthSaysUnpluggedRepluggedAndSilent) {
  WebLab lab;
  const auto health = [&](std::int64_t now) {
    return bench_of(lab.state_json(now), "b1")["bridge"]["health"].get<std::string>();
  };
  lab.on_status("b1", bridge_status("b1", "connected", 0), t0_us);
  lab.on_samples("b1", one_sample("b1", 0, 1000, 0.0), t0_us);
  EXPECT_EQ(health(t0_us), "ok");
  lab.on_status("b1", bridge_status("b1", "disconnected", 0), t0_us + sec_us);
  EXPECT_EQ(health(t0_us + sec_us), "unplugged");
  EXPECT_EQ(health(t0_us + 10 * sec_us), "silent");  // no samples for longer than 5 s
  lab.on_status("b1", bridge_status("b1", "connected", 1), t0_us + 11 * sec_us);
  lab.on_samples("b1", one_sample("b1", 1, 21000, 0.0), t0_us + 11 * sec_us);
  EXPECT_EQ(health(t0_us + 11 * sec_us), "replugged");
  EXPECT_EQ(bench_of(lab.state_json(t0_us + 11 * sec_us), "b1")["bridge"]["reconnects"], 1);
  // Samples without a heartbeat (the bridge's STATUS lost or another publisher).
  lab.on_samples("b2", one_sample("b2", 0, 1000, 0.0), t0_us);
  EXPECT_EQ(bench_of(lab.state_json(t0_us), "b2")["bridge"]["health"], "no heartbeat");
}

TEST(WebLab, OnlyRunsKeptAndBenchesKeptAreRemembered) {
  WebLabOptions o;
  o.runs_kept = 2;
  o.max_benches = 3;
  WebLab lab(o);
  for (int n = 1; n <= 4; ++n) {
    lab.on_run("b1", run_message("b1", n, run_t::STATE_COASTING, 10.0 * n, std::nan("")), t0_us + n);
    lab.on_samples("b1", one_sample("b1", n, 10'000'000 * std::int64_t(n) + 1000, 1.0), t0_us + n);
  }
  EXPECT_FALSE(lab.run_csv("b1", 2));
  EXPECT_TRUE(lab.run_csv("b1", 3));
  EXPECT_TRUE(lab.run_csv("b1", 4));
  const auto j = lab.bench_json("b1", t0_us + 10);
  EXPECT_EQ((*j)["detail"]["earlier"].size(), 1u);
  EXPECT_EQ((*j)["detail"]["earlier"][0]["number"], 3);
  for (int b = 2; b <= 6; ++b) {
    const std::string id = "b" + std::to_string(b);
    lab.on_samples(id, one_sample(id, 0, 1000, 0.0), t0_us + 100 * b);
  }
  EXPECT_EQ(lab.bench_count(), 3u);
  EXPECT_FALSE(lab.knows("b1"));  // the least recently heard
  EXPECT_TRUE(lab.knows("b6"));
}

TEST(WebLab, APageFirstViewIsItsSnapshot) {
  const SimulatedRun r = simulated_run(9);
  WebLabOptions o;
  o.tile_points = 100;
  WebLab lab(o);
  const std::int64_t now = feed_run(lab, r);
  const std::string room = lab.snapshot_event("", now);
  ASSERT_EQ(room.rfind("event: snapshot\ndata: ", 0), 0u);
  ASSERT_EQ(room.substr(room.size() - 2), "\n\n");
  EXPECT_EQ(std::count(room.begin(), room.end(), '\n'), 3);  // one line of JSON
  const Json rj = Json::parse(room.substr(room.find("data: ") + 6));
  EXPECT_EQ(rj["page"], "room");
  EXPECT_LE(rj["samples"]["b1"]["p"].size(), 101u);
  EXPECT_FALSE(rj.contains("detail"));
  const std::string bench = lab.snapshot_event("b1", now);
  const Json bj = Json::parse(bench.substr(bench.find("data: ") + 6));
  EXPECT_EQ(bj["page"], "bench");
  EXPECT_EQ(bj["detail"]["run"]["number"], 1);
  EXPECT_GT(bj["samples"]["b1"]["p"].size(), 1000u);
}

// The plots' points are short in JSON (0.1 ms, 7 significant digits), read back as the decimal.
TEST(WebLab, APlotPointIsShortAndReadsBackAsTheDecimal) {
  EXPECT_EQ(plot_point(12.345678901, 2.8300000000004).dump(), "[12.3457,2.83]");
  EXPECT_EQ(plot_point(0.1 + 0.2, -1.234567891e-7).dump(), "[0.3,-1.234568e-07]");
  EXPECT_EQ(plot_point(1.0, 0.0).dump(), "[1.0,0.0]");
  EXPECT_EQ(plot_point(std::nan(""), 1.0)[0], nullptr);
}

}  // namespace
}  // namespace spindown

namespace spindown {
namespace {

using namespace spindown::test;

// Issue 44 item 3: a run closed early (a reset cut the coast short) or one the fitter doubts never
// takes the tile's headline from the last whole run; it shows only while no whole run has.
TEST(WebLab, ARunClosedEarlyOrDoubtedNeverTakesTheHeadlineFromAWholeRun) {
  const SimulatedRun whole = simulated_run(7, 1);
  WebLab lab;
  std::int64_t now = feed_run(lab, whole);
  fit_t stub = whole.fit;
  stub.run = 2;
  stub.t_cut_s = whole.fit.t_cut_s + 40;
  stub.end = "clock restart";
  for (auto& p : stub.param_value) p *= 3;
  lab.on_fit("b1", stub, now += sec_us);
  EXPECT_EQ(bench_of(lab.state_json(now), "b1")["last_fit"]["run"], 1);
  fit_t doubted = whole.fit;
  doubted.run = 3;
  doubted.t_cut_s = whole.fit.t_cut_s + 80;
  doubted.ndoubts = 1;
  doubted.doubts = {"readings of at most 0.1 V"};
  lab.on_fit("b1", doubted, now += sec_us);
  EXPECT_EQ(bench_of(lab.state_json(now), "b1")["last_fit"]["run"], 1);
  fit_t next = whole.fit;
  next.run = 4;
  next.t_cut_s = whole.fit.t_cut_s + 120;
  lab.on_fit("b1", next, now += sec_us);
  EXPECT_EQ(bench_of(lab.state_json(now), "b1")["last_fit"]["run"], 4);

  WebLab fresh;  // no whole run yet: the stub is what there is
  fresh.on_fit("b2", stub, now);
  EXPECT_EQ(bench_of(fresh.state_json(now), "b2")["last_fit"]["run"], 2);
}

// Issue 44 item 2: a refused FIT for a bench (unsigned, another key) is said on that bench's tile,
// and a refused message naming a bench the lab does not have makes no tile.
TEST(WebLab, ARefusedFitIsSaidOnItsBenchsTileAndMakesNoNewTile) {
  const SimulatedRun whole = simulated_run(7, 1);
  WebLab lab;
  std::int64_t now = feed_run(lab, whole);
  GateResult g;
  g.verdict = GateVerdict::not_signed;
  g.text = "SPINDOWN.b1.FIT from laptop-17: not signed";
  lab.on_refused(g, now += sec_us, {}, "b1");
  const Json state = lab.state_json(now);
  const Json& b = bench_of(state, "b1");
  ASSERT_TRUE(b.contains("refused_recent"));
  EXPECT_NE(b["refused_recent"].get<std::string>().find("laptop-17"), std::string::npos);
  EXPECT_EQ(b["last_fit"]["run"], 1);  // the headline stays the fitter's
  lab.on_refused(g, now, {}, "ghost");
  EXPECT_EQ(lab.bench_count(), 1u);
}

}  // namespace
}  // namespace spindown
