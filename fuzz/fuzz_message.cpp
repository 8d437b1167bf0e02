// One LCM message type (FUZZ_MESSAGE, set per executable by CMake): the input is the encoded
// message. decode_message must accept exactly what decodes and re-encode it byte for byte; a
// decoded message then goes through every consumer the library has for it (the fitter core's
// checks, the live table, the fit message's own consistency checks and JSON).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_check.hpp"
#include "spindown/fit_message.hpp"
#include "spindown/fitter_core.hpp"
#include "spindown/lab_table.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/message_decode.hpp"

#ifndef FUZZ_MESSAGE
#error "FUZZ_MESSAGE must name the message type (samples_t, config_t, run_t, fit_t, explain_t, status_t)"
#endif

namespace {

using namespace spindown;
constexpr std::int64_t now_us = 1'700'000'000'000'000;

// Every published fit must survive its own message round trip.
class CheckingSink : public FitterSink {
 public:
  void run_changed(const run_t& run) override { FUZZ_CHECK(!run.bench.empty()); }
  void fit_ready(const FitResult& r) override {
    FitProvenance about;
    about.bench = r.bench;
    about.bench_source = r.bench_source;
    about.first_seq = r.first_seq;
    about.last_seq = r.last_seq;
    const fit_t msg = to_fit_message(r.fit, about, now_us);
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(msg.getEncodedSize()));
    FUZZ_CHECK(msg.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
    fit_t back{};
    std::string why;
    FUZZ_CHECK(decode_message(back, bytes.data(), static_cast<std::int64_t>(bytes.size()), &why));
    FUZZ_CHECK(from_fit_message(back, &why).has_value());
  }
  void problem(const std::string& text) override { FUZZ_CHECK(!text.empty() && fuzz::valid_utf8(text)); }
};

FitterOptions fitter_options() {
  FitterOptions o;
  o.max_benches = 4;
  return o;
}

template <class Msg>
void feed_fitter(const char* kind, const std::uint8_t* data, std::size_t size, bool decoded) {
  CheckingSink sink;
  FitterCore core(fitter_options(), sink);
  core.on_message(std::string("SPINDOWN.fz.") + kind, data, static_cast<std::int64_t>(size), now_us);
  // The core's own decoding agrees with decode_message about what is a message.
  FUZZ_CHECK((core.counters().decode_errors == 0) == decoded);
  core.finish(now_us + 1'000'000);
}

void render(LabTable& table) {
  (void)table.render(now_us, 80);
  (void)table.render(now_us + 60'000'000);
  (void)table.take_events();
}

[[maybe_unused]] void exercise(const samples_t& m, const std::uint8_t* data, std::size_t size) {
  feed_fitter<samples_t>("SAMPLE", data, size, true);
  LabTable table;
  table.on_samples("fz", m, now_us);
  table.on_samples("fz", m, now_us + 1000);
  render(table);
  (void)quantity_from_samples_code(m.quantity);
}

[[maybe_unused]] void exercise(const config_t& m, const std::uint8_t* data, std::size_t size) {
  feed_fitter<config_t>("CONFIG", data, size, true);
  std::string why;
  if (const auto p = bench_params_from_config(m, &why)) FUZZ_CHECK(p->is_valid(nullptr));
  LabTable table;
  table.on_config("fz", m, now_us);
  render(table);
}

[[maybe_unused]] void exercise(const run_t& m, const std::uint8_t*, std::size_t) {
  FUZZ_CHECK(!run_state_name(m.state).empty());
  LabTable table;
  table.on_run("fz", m, now_us);
  render(table);
}

[[maybe_unused]] void exercise(const fit_t& m, const std::uint8_t*, std::size_t) {
  std::string why;
  const auto fit = from_fit_message(m, &why);
  if (!fit) FUZZ_CHECK(!why.empty());
  const auto json = fit_message_json(m, ReportOptions{}, &why);
  if (json) (void)json->dump();
  (void)fit_coefficients_text(m, true);
  (void)fit_coefficients_text(m, false, false);
  LabTable table;
  table.on_fit("fz", m, now_us);
  render(table);
}

[[maybe_unused]] void exercise(const status_t& m, const std::uint8_t*, std::size_t) {
  LabTable table;
  table.on_status("fz", m, now_us);
  table.on_status(m.instance, m, now_us + 1);
  render(table);
}

[[maybe_unused]] void exercise(const explain_t&, const std::uint8_t*, std::size_t) {}  // no consumer but the round trip

// Bytes the core's own decoder rejects must be rejected by decode_message too, and the core
// must count them.
[[maybe_unused]] void rejected(const samples_t*, const std::uint8_t* data, std::size_t size) {
  feed_fitter<samples_t>("SAMPLE", data, size, false);
}
[[maybe_unused]] void rejected(const config_t*, const std::uint8_t* data, std::size_t size) {
  feed_fitter<config_t>("CONFIG", data, size, false);
}
template <class Msg>
[[maybe_unused]] void rejected(const Msg*, const std::uint8_t*, std::size_t) {}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using Msg = spindown::FUZZ_MESSAGE;
  Msg msg;
  std::string why;
  const bool ok = spindown::decode_message(msg, data, static_cast<std::int64_t>(size), &why);
  if (!ok) {
    FUZZ_CHECK(!why.empty());
    rejected(static_cast<const Msg*>(nullptr), data, size);
    return 0;
  }
  // Re-encoding gives a message that decodes again. Not byte for byte: lcm-gen's encoder writes
  // strings up to their first NUL and always ends them with one, while the decoder keeps every
  // byte but the last (getEncodedSize() counts the whole std::string): an LCM quirk.
  // A message of the older layout (before issue 31's appended fields) decodes with those fields at
  // their defaults and re-encodes in the current layout: larger by at most their fixed size
  // (empty strings, integers, the 32-byte signature), never by more.
  constexpr std::size_t appended_fields_max = 256;
  const int encoded_size = msg.getEncodedSize();
  FUZZ_CHECK(encoded_size >= 8 && static_cast<std::size_t>(encoded_size) <= size + appended_fields_max);
  std::vector<std::uint8_t> again(static_cast<std::size_t>(encoded_size));
  const int written = msg.encode(again.data(), 0, encoded_size);
  FUZZ_CHECK(written >= 8 && written <= encoded_size);
  Msg twice;
  FUZZ_CHECK(spindown::decode_message(twice, again.data(), written, &why));
  exercise(msg, data, size);
  return 0;
}
