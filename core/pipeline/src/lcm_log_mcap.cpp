#include "spindown/lcm_log_mcap.hpp"

#include <cmath>
#include <fmt/format.h>
#include <iterator>
#include <map>
#include <regex>

#include <spindown/fit_t.hpp>
#include <spindown/run_t.hpp>

#include "spindown/fit_message.hpp"
#include "spindown/lcm_log_reader.hpp"
#include "spindown/mcap_writer.hpp"
#include "spindown/message_decode.hpp"
#include "spindown/quantity.hpp"
#include "spindown/sample_stream.hpp"

namespace spindown {

const char* const mcap_sample_json_schema = R"({
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "spindown sample",
  "description": "One sample of SPINDOWN.<bench>.SAMPLE (samples_t), as a row of spindown export --csv",
  "type": "object",
  "properties": {
    "bench": {"type": "string", "description": "bench id"},
    "seq": {"type": "integer", "description": "bridge sequence number of this sample; gaps mean loss"},
    "device_time_s": {"type": "number", "description": "device clock (millis()/micros()), unwrapped, s"},
    "host_time_s": {"type": ["number", "null"], "description": "host time the line was complete, s since the Unix epoch"},
    "value": {"type": ["number", "null"], "description": "reading in unit; null for NaN"},
    "unit": {"type": "string", "description": "V, rpm or rad/s"},
    "raw_adc": {"type": ["integer", "null"], "description": "raw ADC counts; null when the protocol does not carry them"},
    "clock_epoch": {"type": "integer", "description": "device resets seen by the bridge"}
  },
  "required": ["bench", "seq", "device_time_s", "value", "unit"]
})";

const char* const mcap_run_json_schema = R"({
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "spindown run",
  "description": "SPINDOWN.<bench>.RUN (run_t): the life of one run, published by spindown-fitter at each change",
  "type": "object",
  "properties": {
    "bench": {"type": "string"},
    "run": {"type": "integer", "description": "run number on this bench, from 1"},
    "state": {"type": "string", "enum": ["powered", "coasting", "stopped", "abandoned", "unknown"]},
    "state_code": {"type": "integer", "description": "run_t.state: 0 powered, 1 coasting, 2 stopped, 3 abandoned"},
    "t_cut_s": {"type": ["number", "null"], "description": "device time of the power cut, s; null while unknown"},
    "t_stop_s": {"type": ["number", "null"], "description": "device time of the stop, s; null while unknown"},
    "first_seq": {"type": "integer"},
    "last_seq": {"type": "integer"},
    "samples": {"type": "integer"},
    "note": {"type": "string"},
    "lead_in": {"type": "string"}
  },
  "required": ["bench", "run", "state", "state_code"]
})";

const char* const mcap_fit_json_schema = R"({
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "spindown fit",
  "description": "SPINDOWN.<bench>.FIT (fit_t) as spindown fit --json prints a run (docs/design.md section 5); SI units",
  "type": "object",
  "properties": {
    "run": {"type": "integer"},
    "t_cut_s": {"type": ["number", "null"]},
    "t_stop_s": {"type": ["number", "null"]},
    "samples": {"type": "integer"},
    "models": {
      "type": "array",
      "items": {
        "type": "object",
        "properties": {
          "name": {"type": "string", "enum": ["viscous", "coulomb", "combined"]},
          "params": {
            "type": "object",
            "additionalProperties": {
              "type": "object",
              "properties": {
                "value": {"type": ["number", "null"]},
                "stderr": {"type": ["number", "null"]},
                "unit": {"type": "string"}
              }
            }
          },
          "rmse": {"type": ["number", "null"]},
          "residual_unit": {"type": "string"},
          "r2": {"type": ["number", "null"]},
          "aic": {"type": ["number", "null"]},
          "bic": {"type": ["number", "null"]}
        }
      }
    },
    "best": {"type": "string"},
    "bench": {"type": "object", "properties": {"id": {"type": "string"}}},
    "first_seq": {"type": "integer"},
    "last_seq": {"type": "integer"}
  },
  "required": ["run", "models", "best"]
})";

namespace {

// JSON has no NaN or infinity.
void put_number(fmt::memory_buffer& b, double x) {
  if (std::isfinite(x))
    fmt::format_to(std::back_inserter(b), "{}", x);
  else
    fmt::format_to(std::back_inserter(b), "null");
}

std::string json_string(const std::string& s) {
  return Json(s).dump(-1, ' ', false, Json::error_handler_t::replace);
}

std::uint64_t to_ns(std::int64_t us) { return us > 0 ? static_cast<std::uint64_t>(us) * 1000u : 0u; }

enum class Kind { sample, run, fit };

struct Topic {
  bool wanted = false;
  Kind kind = Kind::sample;
  std::uint16_t channel = 0;
  std::uint32_t count = 0;
};

class Converter {
 public:
  Converter(const std::string& path, std::ostream& out, const LcmLogMcapOptions& o)
      : path_(path), o_(o), wanted_(o.bench_regex), writer_(out, {.profile = "", .library = "spindown export --mcap",
                                                                  .chunk_bytes = o.chunk_bytes}) {
    schema_[int(Kind::sample)] = writer_.add_schema("spindown.sample", "jsonschema", mcap_sample_json_schema);
    schema_[int(Kind::run)] = writer_.add_schema("spindown.run", "jsonschema", mcap_run_json_schema);
    schema_[int(Kind::fit)] = writer_.add_schema("spindown.fit", "jsonschema", mcap_fit_json_schema);
  }

  LcmLogMcapResult run(LcmLogReader& reader) {
    LcmLogEvent ev;
    while (reader.next(ev)) {
      if (ev.kind == LcmLogEvent::Kind::problem) {
        // Damage in the file, or an event of an exported topic; not those of other channels
        // (CONFIG, STATUS…) or of benches left out.
        if (ev.channel.empty() || topic(ev)) problem(ev, ev.problem);
        continue;
      }
      Topic* t = topic(ev);
      if (!t) continue;
      if (t->kind == Kind::sample && ev.kind == LcmLogEvent::Kind::samples)
        samples(*t, ev);
      else if (t->kind == Kind::run)
        run_message(*t, ev);
      else if (t->kind == Kind::fit)
        fit_message(*t, ev);
    }
    writer_.close();
    r_.events = reader.events_read();
    r_.bytes = writer_.bytes_written();
    r_.channels = writer_.statistics().channel_count;
    return std::move(r_);
  }

 private:
  void problem(const LcmLogEvent& ev, const std::string& what) {
    ++r_.problems_total;
    if (r_.problems.size() >= o_.max_problems) return;
    if (ev.number > 0)
      r_.problems.push_back(fmt::format("{}: event {} ({}) at byte {}: {}", path_, ev.number, ev.channel,
                                        ev.file_offset, what));
    else
      r_.problems.push_back(fmt::format("{}: at byte {}: {}", path_, ev.file_offset, what));
  }

  // The topic of an event's channel (made on first sight), or null when not exported.
  Topic* topic(const LcmLogEvent& ev) {
    auto it = topics_.find(ev.channel);
    if (it == topics_.end()) {
      Topic t;
      if (const auto name = split_spindown_channel(ev.channel)) {
        const std::string bench(name->bench);
        const bool known = name->kind == "SAMPLE" || name->kind == "RUN" || name->kind == "FIT";
        if (known && std::regex_match(bench, wanted_)) {
          t.wanted = true;
          t.kind = name->kind == "SAMPLE" ? Kind::sample : name->kind == "RUN" ? Kind::run : Kind::fit;
          static const char* const types[] = {"spindown.samples_t", "spindown.run_t", "spindown.fit_t"};
          t.channel = writer_.add_channel(schema_[int(t.kind)], ev.channel, "json",
                                          {{"lcm_channel", std::string(ev.channel)},
                                           {"lcm_type", types[int(t.kind)]},
                                           {"bench", bench}});
        }
      }
      it = topics_.emplace(std::string(ev.channel), t).first;
    }
    return it->second.wanted ? &it->second : nullptr;
  }

  void samples(Topic& t, const LcmLogEvent& ev) {
    const samples_t& m = ev.samples;
    const auto q = quantity_from_samples_code(m.quantity);
    const std::string unit = q ? std::string(quantity_unit(*q)) : fmt::format("code {}", int(m.quantity));
    const std::string bench = json_string(m.bench);
    for (std::int32_t i = 0; i < m.n; ++i) {
      const bool has_host = i < std::int32_t(m.host_time_us.size()) && m.host_time_us[i] > 0;
      const std::int32_t adc = i < std::int32_t(m.raw_adc.size()) ? m.raw_adc[i] : -1;
      const std::int64_t seq = m.seq + i;
      buf_.clear();
      auto out = std::back_inserter(buf_);
      fmt::format_to(out, R"({{"bench":{},"seq":{},"device_time_s":)", bench, seq);
      put_number(buf_, 1e-6 * double(m.device_time_us[i]));
      fmt::format_to(out, R"(,"host_time_s":)");
      if (has_host)
        put_number(buf_, 1e-6 * double(m.host_time_us[i]));
      else
        fmt::format_to(out, "null");
      fmt::format_to(out, R"(,"value":)");
      put_number(buf_, m.value[i]);
      fmt::format_to(out, R"(,"unit":"{}","raw_adc":)", unit);
      if (adc >= 0)
        fmt::format_to(out, "{}", adc);
      else
        fmt::format_to(out, "null");
      fmt::format_to(out, R"(,"clock_epoch":{}}})", m.clock_epoch);
      const std::uint64_t log_ns = has_host ? to_ns(m.host_time_us[i]) : to_ns(ev.log_utime);
      writer_.write_message(t.channel, static_cast<std::uint32_t>(seq), log_ns,
                            m.utime > 0 ? to_ns(m.utime) : log_ns, std::string_view(buf_.data(), buf_.size()));
      ++r_.samples;
    }
  }

  void run_message(Topic& t, const LcmLogEvent& ev) {
    run_t m{};
    std::string why;
    if (!decode_message(m, ev.data, ev.data_size, &why)) {
      problem(ev, fmt::format("does not decode as run_t: {}; not exported", why));
      return;
    }
    buf_.clear();
    auto out = std::back_inserter(buf_);
    fmt::format_to(out, R"({{"bench":{},"run":{},"state":"{}","state_code":{},"t_cut_s":)", json_string(m.bench),
                   m.run, run_state_name(m.state), int(m.state));
    put_number(buf_, m.t_cut_s);
    fmt::format_to(out, R"(,"t_stop_s":)");
    put_number(buf_, m.t_stop_s);
    fmt::format_to(out, R"(,"first_seq":{},"last_seq":{},"samples":{},"note":{},"lead_in":{}}})", m.first_seq,
                   m.last_seq, m.samples, json_string(m.note), json_string(m.lead_in));
    const std::uint64_t log_ns = to_ns(ev.log_utime);
    writer_.write_message(t.channel, t.count++, log_ns, m.utime > 0 ? to_ns(m.utime) : log_ns,
                          std::string_view(buf_.data(), buf_.size()));
    ++r_.runs;
  }

  void fit_message(Topic& t, const LcmLogEvent& ev) {
    fit_t m{};
    std::string why;
    if (!decode_message(m, ev.data, ev.data_size, &why)) {
      problem(ev, fmt::format("does not decode as fit_t: {}; not exported", why));
      return;
    }
    const auto json = fit_message_json(m, ReportOptions{}, &why);
    if (!json) {
      problem(ev, fmt::format("an inconsistent fit_t: {}; not exported", why));
      return;
    }
    const std::string text = json->dump(-1, ' ', false, Json::error_handler_t::replace);
    const std::uint64_t log_ns = to_ns(ev.log_utime);
    writer_.write_message(t.channel, t.count++, log_ns, m.utime > 0 ? to_ns(m.utime) : log_ns, text);
    ++r_.fits;
  }

  std::string path_;
  const LcmLogMcapOptions& o_;
  std::regex wanted_;
  McapWriter writer_;
  std::uint16_t schema_[3] = {};
  std::map<std::string, Topic, std::less<>> topics_;
  fmt::memory_buffer buf_;
  LcmLogMcapResult r_;
};

}  // namespace

LcmLogMcapResult write_lcm_log_mcap(const std::string& log_path, std::ostream& out, const LcmLogMcapOptions& options) {
  LcmLogReader reader(log_path);
  if (!reader.good()) throw LcmLogMcapError(reader.open_error());
  Converter c(log_path, out, options);
  return c.run(reader);
}

}  // namespace spindown
