// spindown-inject: what a student's laptop on the lab network can send, for the integration tests
// of issue 31 (a forger, a replayer). It listens to a bench's SAMPLE channel for the real bridge's
// source (lab, host, session, sequence number) and then publishes one of:
//   --sample: forged SAMPLE messages on SPINDOWN.<bench>.SAMPLE, by default with the real bridge's
//             own source and a sequence number far ahead (--seq, default 2^40);
//   --fit:    a forged FIT on SPINDOWN.<bench>.FIT ("combined", health ok), unsigned unless --key,
//             with the source of the fitter heard on SPINDOWN.*.STATUS when --as-fitter;
//   --replay: every message heard on the bench's channels during --listen, sent again unchanged
//             (signed messages keep their signatures: only the replay window refuses them).
// It prints one line per message sent ("sent CHANNEL …") and exits 0, or 1 when LCM fails.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <spindown/fit_t.hpp>
#include <spindown/samples_t.hpp>
#include <spindown/status_t.hpp>

#include "spindown/clock.hpp"
#include "spindown/lab_key.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/lcm_loop.hpp"
#include "spindown/lcm_url.hpp"
#include "spindown/message_stamp.hpp"
#include "spindown/session_id.hpp"

namespace {

struct Options {
  std::string lcm_url, bench = "bench-1";
  bool sample = false, fit = false, replay = false;
  double listen_s = 3;
  std::int64_t seq = std::int64_t{1} << 40;
  double device_time_s = 1e7;
  double value = 0;
  int count = 1;
  double every_s = 0.02;
  std::string lab, host, key;  // "": the real bridge's lab and host; no key
  bool new_session = false;    // a session of its own instead of the bridge's
  bool as_fitter = false;      // the fitter's source (heard on its STATUS) instead of the bridge's
};

struct Heard {
  bool any = false;
  std::string lab, host;
  std::uint64_t session = 0;
  bool fitter = false;  // a fitter's STATUS heard: its host and session
  std::string fitter_host;
  std::uint64_t fitter_session = 0;
  std::int64_t next_seq = 0;
  std::vector<std::pair<std::string, std::vector<unsigned char>>> messages;  // --replay
};

Heard listen(spindown::LcmLoop& loop, const Options& o) {
  Heard h;
  const std::string prefix = "SPINDOWN\\." + o.bench + "\\.";
  loop.subscribe<spindown::samples_t>(prefix + "SAMPLE", [&](const spindown::samples_t& m) {
    h.any = true;
    h.lab = m.lab;
    h.host = m.source_host;
    h.session = static_cast<std::uint64_t>(m.source_session);
    h.next_seq = m.seq + m.n;
  });
  loop.subscribe<spindown::status_t>("SPINDOWN\\..*\\.STATUS", [&](const spindown::status_t& s) {
    if (s.service != "fitter") return;
    h.fitter = true;
    h.fitter_host = s.source_host;
    h.fitter_session = static_cast<std::uint64_t>(s.source_session);
  });
  if (o.replay)
    loop.subscribe_raw(prefix + "(SAMPLE|CONFIG|RUN|FIT|EXPLAIN|STATUS)", [&](const spindown::LcmMessage& m) {
      const auto* d = static_cast<const unsigned char*>(m.data);
      h.messages.emplace_back(std::string(m.channel), std::vector<unsigned char>(d, d + m.size));
    });
  loop.run({.timeout_s = o.listen_s});
  loop.unsubscribe_all();
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"spindown-inject: forged and replayed messages on a bench's channels, for tests"};
  app.add_option("--lcm-url", o.lcm_url, "LCM URL");
  app.add_option("--bench", o.bench, "the bench whose channels are forged");
  auto* s = app.add_flag("--sample", o.sample, "forged SAMPLE messages");
  auto* f = app.add_flag("--fit", o.fit, "a forged FIT");
  auto* r = app.add_flag("--replay", o.replay, "replay what was heard during --listen");
  s->excludes(f)->excludes(r);
  f->excludes(r);
  app.add_option("--listen", o.listen_s, "seconds to listen first");
  app.add_option("--seq", o.seq, "--sample: the sequence number (default 2^40)");
  app.add_option("--device-time", o.device_time_s, "--sample: device time (s)");
  app.add_option("--value", o.value, "--sample: the value");
  app.add_option("--count", o.count, "messages to send (consecutive sequence numbers)");
  app.add_option("--every", o.every_s, "seconds between them");
  app.add_option("--lab", o.lab, "lab name to claim (default: the bridge's)");
  app.add_option("--host", o.host, "host name to claim (default: the bridge's)");
  app.add_flag("--new-session", o.new_session, "a session of its own, not the bridge's");
  app.add_flag("--as-fitter", o.as_fitter, "the source of the fitter heard on STATUS (host, session)");
  app.add_option("--key", o.key, "sign with this key file (a wrong key, for tests)");
  CLI11_PARSE(app, argc, argv);
  if (!o.sample && !o.fit && !o.replay) {
    fmt::print(stderr, "spindown-inject: one of --sample, --fit, --replay\n");
    return 2;
  }
  spindown::LcmLoop loop(o.lcm_url);
  if (!loop.good()) {
    fmt::print(stderr, "spindown-inject: cannot start LCM\n");
    return 1;
  }
  const Heard h = listen(loop, o);
  if (o.replay) {
    for (const auto& [channel, bytes] : h.messages) {
      loop.lcm().publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
    fmt::print("sent {} messages again (replay)\n", h.messages.size());
    return 0;
  }
  std::optional<spindown::LabKey> key;
  if (!o.key.empty()) {
    std::string why;
    key = spindown::load_lab_key(o.key, &why);
    if (!key) {
      fmt::print(stderr, "spindown-inject: {}\n", why);
      return 2;
    }
  }
  spindown::SourceIdentity id;
  id.lab = !o.lab.empty() ? o.lab : h.any ? h.lab : std::string("lab");
  id.sent_to = spindown::lcm_destination(o.lcm_url);
  id.host = !o.host.empty() ? o.host : h.any ? h.host : std::string("laptop");
  id.session = o.new_session || !h.any ? spindown::new_session_id() : h.session;
  if (o.as_fitter && h.fitter) {
    id.host = h.fitter_host;
    id.session = h.fitter_session;
  }
  id.start_utime = spindown::wall_us();
  spindown::MessageStamp stamp(id, key);
  for (int i = 0; i < o.count; ++i) {
    const std::int64_t now = spindown::wall_us();
    if (o.sample) {
      spindown::samples_t m{};
      m.utime = now;
      m.bench = o.bench;
      m.seq = o.seq + i;
      m.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
      m.n = 1;
      m.device_time_us = {static_cast<std::int64_t>(std::llround((o.device_time_s + 0.02 * i) * 1e6))};
      m.host_time_us = {now};
      m.value = {o.value};
      m.raw_adc = {-1};
      const std::string channel = spindown::channel_name(o.bench, spindown::ChannelKind::sample);
      const auto bytes = stamp.encode(channel, m);
      loop.lcm().publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      fmt::print("sent {} seq {} as {} lab '{}'\n", channel, m.seq, spindown::source_text(id.host, id.session), id.lab);
    } else {
      spindown::fit_t m{};
      m.utime = now;
      m.bench = o.bench;
      m.run = 99;
      m.t_cut_s = 1;
      m.t_stop_s = 20;
      m.samples = 900;
      m.inertia_kg_m2 = 1.12687602e-5;
      m.kb_v_s_per_rad = 1 / 123.569311;
      m.bench_source = "config";
      m.residual_unit = "V";
      m.nmodels = 1;
      m.model = {"combined"};
      m.rmse = {0.001};
      m.r2 = {0.9999};
      m.aic = {-1};
      m.bic = {-1};
      m.t_stop_pred_s = {19};
      m.converged = {true};
      m.model_samples = {900};
      m.model_message = {""};
      m.model_reduced_chi2 = {1};
      m.nparams = 2;
      m.param_model = {0, 0};
      m.param_name = {"c3", "c4"};
      m.param_value = {1.0e-7, 5.0e-5};
      m.param_stderr = {1e-9, 1e-7};
      m.param_unit = {"N*m*s/rad", "N*m"};
      m.param_bench_error = {0, 0};
      m.best = "combined";
      m.best_reason = "forged";
      m.verdict = "ok";
      m.verdict_reason = "friction as expected (forged)";
      m.lead_in = "zeros";
      m.end = "stopped";
      m.t_end_s = 21;
      const std::string channel = spindown::channel_name(o.bench, spindown::ChannelKind::fit);
      const auto bytes = stamp.encode(channel, m);
      loop.lcm().publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
      fmt::print("sent {} run 99 (forged, health ok) as {} lab '{}'\n", channel,
                 spindown::source_text(id.host, id.session), id.lab);
    }
    if (i + 1 < o.count) std::this_thread::sleep_for(std::chrono::duration<double>(o.every_s));
  }
  return 0;
}
