// spindown-run-publisher: publishes generated spin-down runs for many benches as samples_t and
// config_t on LCM (as spindown-bridge would), optionally with faults, then listens for the
// fitter's FIT messages and reports how long after each run's true stop its fit arrived.
// For integration tests and the fitter benchmark; only ever point it at a private LCM URL.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <fstream>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <queue>
#include <thread>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/fit_t.hpp>
#include <spindown/samples_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/synthetic_run.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using spindown::wall_us;

struct Options {
  std::string lcm_url;
  int benches = 3;
  int runs = 2;
  std::string prefix = "bench";
  double period_s = 0.020;
  double speed = 1.0;          // device seconds per host second
  int batch = 1;               // samples per message
  double stagger_s = -1;       // start offset between benches (default: spread over one run)
  int config_benches = -1;     // the first N benches publish CONFIG (default all)
  double config_inertia = 0;   // J in CONFIG (0: lab default)
  double wait_fits_s = 0;      // listen for FIT this long after the last sample at most
  std::string truth_path, report_path;
  std::uint64_t seed = 1;
  // Faults: every N-th message (0 = never).
  long nan_every = 0, dup_every = 0, gap_every = 0, garbage_every = 0, truncate_every = 0, backwards_every = 0,
       new_bench_every = 0, invalid_bench_every = 0;
};

struct TruthRun {
  double t_cut_s = 0, t_stop_s = 0;  // device time
  bool stopped = false;
};

struct Sample {
  std::int64_t t_us;
  double value;
  std::int32_t adc;
};

struct BenchPlan {
  std::string id;
  std::vector<Sample> samples;
  std::vector<TruthRun> truth;
  double host_offset_s = 0;  // host seconds after the start at which device time t0 is published
  std::int64_t t0_us = 0;
  std::size_t next = 0;
  std::int64_t seq = 0;
  double host_at(std::int64_t t_us, double speed) const { return host_offset_s + 1e-6 * double(t_us - t0_us) / speed; }
};

BenchPlan make_plan(const Options& o, int b) {
  BenchPlan p;
  p.id = fmt::format("{}{:03d}", o.prefix, b);
  double t0_ms = 1000.0 + 37.0 * b;
  for (int r = 0; r < o.runs; ++r) {
    spindown::SyntheticRunSpec spec;
    spec.seed = o.seed * 1000003ull + std::uint64_t(b) * 101ull + std::uint64_t(r);
    spec.period_s = o.period_s;
    spec.e0_v = 2.4 + 0.1 * ((b + r) % 8);
    spec.lead_in = (b + r) % 3 == 0 ? spindown::LeadIn::supply : spindown::LeadIn::zeros;
    // Powered, the pin reads the supply, above the back-EMF by the winding's I·R drop (3.1 V of
    // back-EMF under a 3.0 V supply, as this plan once made, is no motor: it rises at the "cut").
    spec.supply_v = spec.e0_v + 0.2;
    spec.friction.viscous = 1.822e-7 * (0.8 + 0.05 * (b % 9));
    spec.friction.coulomb = 1.1389e-4 * (0.8 + 0.05 * ((b + 3) % 9));
    spec.t0_ms = t0_ms;
    const spindown::SyntheticRun run = spindown::make_synthetic_run(spec);
    for (std::size_t i = 0; i < run.t_ms.size(); ++i)
      p.samples.push_back({static_cast<std::int64_t>(std::llround(run.t_ms[i] * 1000.0)), run.volts[i], run.adc[i]});
    p.truth.push_back({run.t_cut_ms / 1000.0, run.t_cut_ms / 1000.0 + run.t_stop_s, run.stopped});
    t0_ms = run.t_ms.back() + spec.period_s * 1000.0;
  }
  p.t0_us = p.samples.empty() ? 0 : p.samples.front().t_us;
  return p;
}

struct FitSeen {
  std::string bench;
  int run = 0;
  double t_cut_s = 0, t_stop_s = 0, latency_s = 0;
  std::int64_t recv_us = 0;
  Clock::time_point recv;
  std::string best, bench_source;
  int samples = 0;
};

// Every FIT on the URL, collected by an LCM loop on its own thread.
class FitListener {
 public:
  explicit FitListener(const std::string& url) : loop_(url) {
    if (loop_.good())
      loop_.subscribe<spindown::fit_t>("SPINDOWN\\..*\\.FIT", [this](const spindown::fit_t& m, const spindown::LcmMessage& r) {
        on_fit(r.recv_utime, m);
      });
  }
  bool good() const { return loop_.good(); }
  void start() {
    thread_ = std::thread([this] { loop_.run({.max_wait_ms = 50, .max_failures = -1}); });
  }
  void stop() {
    loop_.stop();
    if (thread_.joinable()) thread_.join();
  }
  std::vector<FitSeen> fits() {
    std::lock_guard lock(mu_);
    return fits_;
  }
  std::size_t count() {
    std::lock_guard lock(mu_);
    return fits_.size();
  }

 private:
  void on_fit(std::int64_t recv_utime, const spindown::fit_t& m) {
    FitSeen f{m.bench, m.run, m.t_cut_s, m.t_stop_s, m.latency_s, recv_utime, Clock::now(),
              m.best, m.bench_source, m.samples};
    std::lock_guard lock(mu_);
    fits_.push_back(std::move(f));
  }
  spindown::LcmLoop loop_;
  std::thread thread_;
  std::mutex mu_;
  std::vector<FitSeen> fits_;
};

double quantile(std::vector<double> v, double p) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const double x = p * double(v.size() - 1);
  const std::size_t i = static_cast<std::size_t>(x);
  return i + 1 < v.size() ? v[i] + (x - double(i)) * (v[i + 1] - v[i]) : v[i];
}

// The median, the 95th percentile and the largest of v (NaN when empty).
nlohmann::json quantiles(const std::vector<double>& v) {
  return {{"p50", quantile(v, 0.5)}, {"p95", quantile(v, 0.95)}, {"max", quantile(v, 1.0)}};
}

void add_options(CLI::App& app, Options& o) {
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (use a private one: udpm://239.255.76.67:7667?ttl=0 in a netns)")
      ->required();
  app.add_option("--benches", o.benches, "number of benches")->check(CLI::Range(1, 10000));
  app.add_option("--runs", o.runs, "runs per bench")->check(CLI::Range(1, 1000));
  app.add_option("--prefix", o.prefix, "bench id prefix (ids are PREFIX000, PREFIX001, …)");
  app.add_option("--period", o.period_s, "sample period (s)")->check(CLI::Range(0.001, 1.0));
  app.add_option("--speed", o.speed, "device seconds per host second (1 = real time)")->check(CLI::Range(0.01, 1000.0));
  app.add_option("--batch", o.batch, "samples per message")->check(CLI::Range(1, 1000));
  app.add_option("--stagger", o.stagger_s, "host seconds between bench starts (default: spread over 20 s)");
  app.add_option("--config-benches", o.config_benches, "only the first N benches publish CONFIG (default all)");
  app.add_option("--config-inertia", o.config_inertia, "J in CONFIG (kg·m², default the lab's)");
  app.add_option("--wait-fits", o.wait_fits_s, "after the last sample, wait this long at most for every FIT");
  app.add_option("--truth", o.truth_path, "write the runs' true cut/stop times (JSON)");
  app.add_option("--report", o.report_path, "write the FIT latency report (JSON; also on stdout)");
  app.add_option("--seed", o.seed, "random seed");
  app.add_option("--nan-every", o.nan_every, "fault: a NaN value in every N-th message");
  app.add_option("--dup-every", o.dup_every, "fault: every N-th message published twice");
  app.add_option("--gap-every", o.gap_every, "fault: every N-th message not published (a sequence gap)");
  app.add_option("--garbage-every", o.garbage_every, "fault: a message with a wrong fingerprint after every N-th");
  app.add_option("--truncate-every", o.truncate_every, "fault: a truncated samples_t after every N-th");
  app.add_option("--backwards-every", o.backwards_every, "fault: a stale sample (time going back) in every N-th");
  app.add_option("--new-bench-every", o.new_bench_every, "fault: a message from a never-seen bench id after every N-th");
  app.add_option("--invalid-bench-every", o.invalid_bench_every, "fault: a message on an invalid bench id");
}

// Every bench's plan, their starts staggered.
std::vector<BenchPlan> make_plans(const Options& o) {
  std::vector<BenchPlan> plans;
  for (int b = 0; b < o.benches; ++b) plans.push_back(make_plan(o, b));
  const double stagger = o.stagger_s >= 0 ? o.stagger_s : 20.0 / o.benches / o.speed;
  for (int b = 0; b < o.benches; ++b) plans[b].host_offset_s = 0.2 + b * stagger;
  return plans;
}

// The runs' true cut and stop times by bench.
nlohmann::json truth_json(const std::vector<BenchPlan>& plans) {
  nlohmann::json truth = nlohmann::json::object();
  for (const BenchPlan& p : plans) {
    nlohmann::json runs = nlohmann::json::array();
    for (const TruthRun& t : p.truth)
      runs.push_back({{"t_cut_s", t.t_cut_s}, {"t_stop_s", t.t_stop_s}, {"stopped", t.stopped}});
    truth[p.id] = std::move(runs);
  }
  return truth;
}

// The true run a FIT is of: the nearest cut on its bench, if within a second.
const TruthRun* true_run_of(const BenchPlan& p, const FitSeen& f) {
  const TruthRun* best = nullptr;
  for (const TruthRun& t : p.truth)
    if (!best || std::abs(t.t_cut_s - f.t_cut_s) < std::abs(best->t_cut_s - f.t_cut_s)) best = &t;
  return best && std::abs(best->t_cut_s - f.t_cut_s) < 1.0 ? best : nullptr;
}

// The benches' plans published on LCM as spindown-bridge would (each bench's CONFIG, then its
// samples in batches at their host times, with the faults asked for), and the FITs that came
// back matched with the true runs.
class RunPublisher {
 public:
  RunPublisher(lcm::LCM& lcm, const Options& o) : lcm_(lcm), o_(o), plans_(make_plans(o)) {
    for (const BenchPlan& p : plans_) expected_ += p.truth.size();
  }
  std::size_t expected_fits() const { return expected_; }
  const std::vector<BenchPlan>& plans() const { return plans_; }

  void publish() {
    start_ = Clock::now();
    send_configs();
    auto next_config = start_ + std::chrono::seconds(3);
    // Benches in order of their next message's host time.
    using Item = std::pair<double, int>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> due;
    for (int b = 0; b < o_.benches; ++b) due.push({next_due(plans_[b]), b});
    while (!due.empty()) {
      const auto [when, b] = due.top();
      due.pop();
      std::this_thread::sleep_until(start_ + std::chrono::nanoseconds(static_cast<std::int64_t>(when * 1e9)));
      if (Clock::now() >= next_config) {
        send_configs();
        next_config += std::chrono::seconds(3);
      }
      BenchPlan& p = plans_[b];
      publish_next_batch(p);
      if (p.next < p.samples.size()) due.push({next_due(p), b});
    }
    publish_s_ = std::chrono::duration<double>(Clock::now() - start_).count();
    fmt::print(stderr, "spindown-run-publisher: {} messages for {} benches ({} runs) in {:.1f} s\n", messages_,
               o_.benches, expected_, publish_s_);
  }

  // Each FIT with its true run (nearest cut on the same bench): how long after the true stop it
  // arrived, and the latencies' quantiles.
  nlohmann::json report(const std::vector<FitSeen>& fits) const {
    nlohmann::json list = nlohmann::json::array();
    std::vector<double> after_stop, latency;
    std::map<std::string, int> plan_of;
    for (int b = 0; b < o_.benches; ++b) plan_of[plans_[b].id] = b;
    std::size_t matched = 0;
    for (const FitSeen& f : fits) {
      nlohmann::json j = {{"bench", f.bench}, {"run", f.run}, {"t_cut_s", f.t_cut_s}, {"latency_s", f.latency_s},
                          {"best", f.best}, {"bench_source", f.bench_source}, {"samples", f.samples}};
      if (auto it = plan_of.find(f.bench); it != plan_of.end()) {
        const BenchPlan& p = plans_[it->second];
        if (const TruthRun* truth = true_run_of(p, f)) {
          ++matched;
          const double host_stop = p.host_at(static_cast<std::int64_t>(truth->t_stop_s * 1e6), o_.speed);
          const double arrived = std::chrono::duration<double>(f.recv - start_).count();
          const double after = arrived - host_stop;
          j["true_t_cut_s"] = truth->t_cut_s;
          j["true_t_stop_s"] = truth->t_stop_s;
          j["after_true_stop_s"] = after;
          j["after_true_stop_device_s"] = after * o_.speed;
          after_stop.push_back(after);
        }
      }
      latency.push_back(f.latency_s);
      list.push_back(std::move(j));
    }
    nlohmann::json report;
    report["expected_fits"] = expected_;
    report["fits"] = list.size();
    report["matched"] = matched;
    report["messages"] = messages_;
    report["benches"] = o_.benches;
    report["publish_s"] = publish_s_;
    report["speed"] = o_.speed;
    report["latency_s"] = quantiles(latency);
    report["after_true_stop_s"] = quantiles(after_stop);
    report["fit_list"] = std::move(list);
    return report;
  }

 private:
  // The host time (seconds after the start) of the bench's next message: when its last sample is due.
  double next_due(const BenchPlan& p) const {
    const std::size_t last = std::min(p.samples.size(), p.next + std::size_t(o_.batch)) - 1;
    return p.host_at(p.samples[last].t_us, o_.speed);
  }

  void send_configs() {
    for (int b = 0; b < o_.benches; ++b) {
      if (o_.config_benches >= 0 && b >= o_.config_benches) continue;
      const spindown::config_t c = config_of(plans_[b]);
      lcm_.publish(spindown::channel_name(plans_[b].id, spindown::ChannelKind::config), &c);
    }
  }

  spindown::config_t config_of(const BenchPlan& p) const {
    spindown::config_t c{};
    c.utime = wall_us();
    c.bench = p.id;
    c.inertia_kg_m2 = o_.config_inertia > 0 ? o_.config_inertia : 1.12687602e-5;
    c.inertia_source = o_.config_inertia > 0 ? "run-publisher --config-inertia" : "lab flywheel + rotor";
    c.kb_v_s_per_rad = 1.0 / 123.569311;
    c.kb_source = "speed constant 1180 rpm/V";
    c.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
    c.adc_volts_per_count = 5.0 / 1024;
    c.adc_bits = 10;
    c.firmware = "run-publisher";
    c.protocol = "lab-tsv";
    c.sample_period_s = o_.period_s;
    c.baud = 9600;
    c.device = "generated";
    c.host = "localhost";
    c.inertia_rel_error = 0;
    c.kb_rel_error = 0;
    return c;
  }

  // The bench's next batch of samples as one samples_t, published with the faults due.
  void publish_next_batch(BenchPlan& p) {
    const std::size_t end = std::min(p.samples.size(), p.next + std::size_t(o_.batch));
    msg_ = {};
    msg_.utime = wall_us();
    msg_.bench = p.id;
    msg_.seq = p.seq;
    msg_.clock_epoch = 0;
    msg_.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
    for (std::size_t i = p.next; i < end; ++i) {
      msg_.device_time_us.push_back(p.samples[i].t_us);
      msg_.host_time_us.push_back(msg_.utime);
      msg_.value.push_back(p.samples[i].value);
      msg_.raw_adc.push_back(p.samples[i].adc);
    }
    msg_.n = static_cast<std::int32_t>(end - p.next);
    p.seq += msg_.n;
    p.next = end;
    ++messages_;
    publish_with_faults(p);
  }

  void publish_with_faults(const BenchPlan& p) {
    const auto every = [&](long n) { return n > 0 && messages_ % n == 0; };
    if (every(o_.nan_every)) msg_.value[0] = std::nan("");
    if (every(o_.backwards_every) && msg_.n > 0) msg_.device_time_us[0] -= 5'000'000;
    const std::string channel = spindown::channel_name(p.id, spindown::ChannelKind::sample);
    if (!every(o_.gap_every)) lcm_.publish(channel, &msg_);
    if (every(o_.dup_every)) lcm_.publish(channel, &msg_);
    if (every(o_.garbage_every)) {
      const std::string junk = "this is not a samples_t message";
      lcm_.publish(channel, junk.data(), static_cast<unsigned>(junk.size()));
    }
    if (every(o_.truncate_every)) {
      std::vector<unsigned char> buf(static_cast<std::size_t>(msg_.getEncodedSize()));
      msg_.encode(buf.data(), 0, static_cast<int>(buf.size()));
      lcm_.publish(channel, buf.data(), static_cast<unsigned>(buf.size() / 2));
    }
    if (every(o_.new_bench_every)) {
      spindown::samples_t other = msg_;
      other.bench = fmt::format("stray{}", ++new_bench_counter_);
      lcm_.publish(spindown::channel_name(other.bench, spindown::ChannelKind::sample), &other);
    }
    if (every(o_.invalid_bench_every)) lcm_.publish("SPINDOWN.bad!bench.SAMPLE", &msg_);
  }

  lcm::LCM& lcm_;
  const Options& o_;
  std::vector<BenchPlan> plans_;
  std::size_t expected_ = 0;  // FITs: one per run
  Clock::time_point start_;
  double publish_s_ = 0;
  long messages_ = 0, new_bench_counter_ = 0;
  spindown::samples_t msg_{};  // reused: one message at a time
};

// Until every expected FIT came, or wait_s passed.
void wait_for_fits(FitListener& listener, double wait_s, std::size_t expected) {
  const auto deadline = Clock::now() + std::chrono::milliseconds(static_cast<std::int64_t>(wait_s * 1000));
  while (Clock::now() < deadline && listener.count() < expected)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"spindown-run-publisher: generated runs -> SPINDOWN.<bench>.SAMPLE|CONFIG; FIT latency report"};
  Options o;
  add_options(app, o);
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(o.lcm_url);
  FitListener listener(o.lcm_url);
  if (!lcm.good() || !listener.good()) {
    fmt::print(stderr, "spindown-run-publisher: cannot start LCM at {}\n", o.lcm_url);
    return 1;
  }
  listener.start();
  RunPublisher publisher(lcm, o);
  publisher.publish();
  wait_for_fits(listener, o.wait_fits_s, publisher.expected_fits());
  listener.stop();

  const nlohmann::json report = publisher.report(listener.fits());
  if (!o.truth_path.empty()) std::ofstream(o.truth_path) << truth_json(publisher.plans()).dump(1) << '\n';
  if (!o.report_path.empty()) std::ofstream(o.report_path) << report.dump(1) << '\n';
  nlohmann::json summary = report;
  summary.erase("fit_list");
  std::cout << summary.dump(1) << std::endl;
  return 0;
}
