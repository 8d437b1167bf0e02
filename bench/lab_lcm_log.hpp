#pragma once
// Lab traffic written straight to an LCM event log, as spindown-logger would have recorded it:
// benches publishing one SAMPLE message every 20 ms (batch samples each; the lab bridge sends
// 1), CONFIG at the start and every 3 s, the benches' messages interleaved in time order. Each
// bench coasts run after run (generated like the virtual bench: lab friction, 4 mV noise, 1 %
// ripple, 10-bit ADC, 2 decimals), so a refit segments and fits every run. Used by
// make_lcm_log (bench/refit_throughput.sh) and the LCM log / refit benchmarks.
#include <algorithm>
#include <cstdint>
#include <fmt/format.h>
#include <lcm/lcm-cpp.hpp>
#include <queue>
#include <stdexcept>
#include <string>
#include <vector>

#include <spindown/config_t.hpp>
#include <spindown/samples_t.hpp>

#include "spindown/lcm_channels.hpp"
#include "lab_messages.hpp"  // tests/support
#include "spindown/synthetic_run.hpp"

namespace bench_log {

inline constexpr std::int64_t host_epoch_us = 1'763'000'000'000'000;  // Nov 2025: a plausible wall clock

struct BenchStream {
  std::string id;
  std::uint64_t seed = 0;
  spindown::SyntheticRun run;  // the current coast
  std::size_t next = 0;        // next sample in run
  std::int64_t seq = 0;
  double t0_ms = 1000;         // device time where the next run starts
  std::int64_t host_offset_us = 0;
  std::int64_t next_config_us = 0;

  void new_run() {
    spindown::SyntheticRunSpec spec;
    spec.seed = seed++;
    spec.t0_ms = t0_ms;
    spec.e0_v = 2.5 + 0.1 * double(seed % 9);
    spec.lead_in_s = 1.0;
    spec.tail_s = 2.0;
    spec.noise_v = 0.004;
    spec.ripple = 0.01;
    run = spindown::make_synthetic_run(spec);
    next = 0;
    t0_ms = run.t_ms.back() + 20;
  }
  std::int64_t host_us() const {
    return host_epoch_us + host_offset_us + static_cast<std::int64_t>(run.t_ms[next] * 1000.0);
  }
};

template <class Msg>
void write_event(lcm::LogFile& log, const std::string& channel, std::int64_t utime, const Msg& msg,
                 std::vector<unsigned char>& buf) {
  buf.resize(static_cast<std::size_t>(msg.getEncodedSize()));
  msg.encode(buf.data(), 0, static_cast<int>(buf.size()));
  lcm::LogEvent ev{};
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<std::int32_t>(buf.size());
  ev.data = buf.data();
  if (log.writeEvent(&ev) != 0) throw std::runtime_error("write failed");
}

// The CONFIG each bench sends: the lab's motor and flywheel, as a bridge publishes it.
inline spindown::config_t make_config(const std::string& bench, std::int64_t utime) {
  return spindown::test::lab_config(bench, 1.12687602e-5, 1.0 / 123.569311, utime);
}

struct LabLogStats {
  long long samples = 0, messages = 0, runs = 0;
};

// Writes about `samples` samples (exactly, the last run cut short) to path; throws on failure.
inline LabLogStats write_lab_lcm_log(const std::string& path, long long samples, int benches, int batch) {
  lcm::LogFile log(path, "w");
  if (!log.good()) throw std::runtime_error("cannot write " + path);
  std::vector<BenchStream> streams(static_cast<std::size_t>(benches));
  for (int b = 0; b < benches; ++b) {
    BenchStream& s = streams[static_cast<std::size_t>(b)];
    s.id = fmt::format("bench{:03d}", b);
    s.seed = 1000u * static_cast<std::uint64_t>(b + 1);
    s.host_offset_us = 7'000LL * b;  // benches not in lockstep
    s.new_run();
  }
  // Benches in order of their next message's host time.
  using Item = std::pair<std::int64_t, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> due;
  for (int b = 0; b < benches; ++b) due.push({streams[static_cast<std::size_t>(b)].host_us(), b});

  std::vector<unsigned char> buf;
  spindown::samples_t msg{};
  msg.quantity = spindown::samples_t::QUANTITY_BACK_EMF_V;
  msg.clock_epoch = 0;
  LabLogStats st;
  st.runs = benches;
  while (st.samples < samples) {  // bounded: every pass writes at least one sample
    const auto [utime, b] = due.top();
    due.pop();
    BenchStream& s = streams[static_cast<std::size_t>(b)];
    if (utime >= s.next_config_us) {
      write_event(log, spindown::channel_name(s.id, spindown::ChannelKind::config), utime, make_config(s.id, utime),
                  buf);
      s.next_config_us = utime + 3'000'000;
    }
    const std::size_t end = std::min({s.run.t_ms.size(), s.next + std::size_t(batch),
                                      s.next + static_cast<std::size_t>(samples - st.samples)});
    msg.bench = s.id;
    msg.seq = s.seq;
    msg.device_time_us.clear();
    msg.host_time_us.clear();
    msg.value.clear();
    msg.raw_adc.clear();
    for (std::size_t i = s.next; i < end; ++i) {
      msg.device_time_us.push_back(static_cast<std::int64_t>(s.run.t_ms[i] * 1000.0));
      msg.host_time_us.push_back(host_epoch_us + s.host_offset_us + static_cast<std::int64_t>(s.run.t_ms[i] * 1000.0));
      msg.value.push_back(s.run.volts[i]);
      msg.raw_adc.push_back(s.run.adc[i]);
    }
    msg.n = static_cast<std::int32_t>(end - s.next);
    msg.utime = msg.host_time_us.back();  // published when the batch is complete
    write_event(log, spindown::channel_name(s.id, spindown::ChannelKind::sample), msg.utime, msg, buf);
    st.samples += msg.n;
    s.seq += msg.n;
    ++st.messages;
    s.next = end;
    if (s.next >= s.run.t_ms.size()) {
      s.new_run();
      ++st.runs;
    }
    due.push({s.host_us(), b});
  }
  return st;
}

}  // namespace bench_log
