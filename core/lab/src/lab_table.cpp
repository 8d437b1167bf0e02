#include "spindown/lab_table.hpp"

#include <algorithm>
#include <cctype>
#include <functional>
#include <array>
#include <cmath>
#include <ctime>
#include <fmt/format.h>
#include <limits>

#include "spindown/fit_message.hpp"
#include "spindown/fit_report.hpp"
#include "spindown/lab_units.hpp"
#include "spindown/lcm_status.hpp"

namespace spindown {

namespace {

// Counters worth a column per service; any other service shows its first few.
constexpr std::array<std::string_view, 7> fitter_counters{"samples", "runs", "fits", "fit_failures",
                                                          "seq_gaps", "samples_lost", "decode_errors"};
constexpr std::array<std::string_view, 6> logger_counters{"events", "files", "drops", "write_errors",
                                                          "seq_gaps", "samples_missing"};
constexpr std::size_t other_counters_shown = 5;

bool is_friction_coefficient(std::string_view name) {
  return name.size() == 2 && name[0] == 'c' && name[1] >= '1' && name[1] <= '9';
}

std::string seconds_text(double s) {
  if (!std::isfinite(s)) return "-";
  if (s < 10) return fmt::format("{:.1f} s", s);
  if (s < 600) return fmt::format("{:.0f} s", s);
  return fmt::format("{:.0f} min", s / 60);
}

std::string age_text(std::int64_t last_us, std::int64_t now_us, double stale_s) {
  if (last_us <= 0) return "-";
  const double age = std::max(0.0, 1e-6 * double(now_us - last_us));
  return seconds_text(age) + (age > stale_s ? " !" : "");
}

std::string run_state_text(const LabBenchRow& r, bool unfollowed, std::int64_t now_us) {
  if (!r.has_run) return r.has_samples ? "-" : "no data";
  if (unfollowed)
    return fmt::format("{} not followed (no fitter for {:.0f} s)", r.run, 1e-6 * double(now_us - r.last_run_us));
  return fmt::format("{} {}{}", r.run, run_state_name(r.run_state), r.run_partial ? " (partial)" : "");
}

std::string rmse_text(const LabBenchRow& r) {
  if (!r.has_fit || r.best.empty() || !std::isfinite(r.rmse)) return "-";
  return fmt::format("{:.3g} {}", r.rmse, r.residual_unit);
}

std::string bridge_text(const LabBenchRow& r) {
  if (!r.has_bridge) return "no bridge status";
  return fmt::format("{} {}/{} {:.0f} Hz", r.bridge_state, r.lines_good, r.lines_bad, r.rate_hz);
}

// The bridge in a few characters: its rate and bad lines while connected (the normal state, not
// said), else its state.
std::string bridge_short(const LabBenchRow& r) {
  if (!r.has_bridge) return "-";
  if (r.bridge_state != "connected") return r.bridge_state;
  return r.lines_bad ? fmt::format("{:.0f} Hz, {} bad", r.rate_hz, r.lines_bad) : fmt::format("{:.0f} Hz", r.rate_hz);
}

std::string gaps_text(const LabBenchRow& r) {
  if (!r.has_samples) return "-";
  if (r.seq_gaps == 0) return "0";
  return fmt::format("{} ({} lost)", r.seq_gaps, r.samples_missing);
}

std::string_view state_short(std::int8_t state) {
  switch (state) {
    case run_t::STATE_POWERED: return "power";
    case run_t::STATE_COASTING: return "coast";
    case run_t::STATE_STOPPED: return "stop";
    case run_t::STATE_ABANDONED: return "aband";
    default: return "?";
  }
}

std::string run_short(const LabBenchRow& r, bool unfollowed) {
  if (!r.has_run) return r.has_samples ? "-" : "no data";
  if (unfollowed) return fmt::format("{} not followed", r.run);
  return fmt::format("{} {}{}", r.run, state_short(r.run_state), r.run_partial ? " (p)" : "");
}

// The last fit: its run and best model (and whether J/K_b were defaults).
std::string fit_text(const LabBenchRow& r) {
  if (!r.has_fit) return "-";
  if (r.best.empty()) return fmt::format("run {}: no model converged", r.fit_run);
  std::string s = fmt::format("run {}{} {}", r.fit_run, r.fit_partial ? " (partial)" : "", r.best);
  if (!r.fit_doubt.empty()) s += " NOT VERIFIED";
  if (r.bench_source != "config" && !r.bench_source.empty()) s += " (default J/K_b)";
  return s;
}

std::string fit_short(const LabBenchRow& r) {
  if (!r.has_fit) return "-";
  const std::string model = r.best.empty() ? "none" : r.best.substr(0, 4);
  return fmt::format("{}{} {}{}{}", r.fit_run, r.fit_partial ? "p" : "", model,
                     r.bench_source != "config" && !r.bench_source.empty() ? "*" : "",
                     r.fit_doubt.empty() ? "" : " NOT VERIFIED");
}

std::string health_text(const LabBenchRow& r) {
  if (!r.has_fit || r.health.empty()) return "-";
  std::string h = r.health;
  for (char& c : h) c = c == '_' ? ' ' : static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return h;
}

// A power of ten for a column of coefficients, so that its cells read 1.822±0.011 (the scale said
// once, under the table): the largest value's, 0 when there is none. Lab units are left unscaled.
int column_exponent(const std::map<std::string, LabBenchRow, std::less<>>& rows, double LabBenchRow::*value,
                    bool lab_units) {
  double top = 0;
  for (const auto& [id, r] : rows)
    if (r.has_fit && std::isfinite(r.*value)) top = std::max(top, std::abs(r.*value));
  if (!(top > 0) || lab_units) return 0;
  return static_cast<int>(std::floor(std::log10(top)));
}

std::string coefficient_cell(double value, double error, int exponent) {
  if (!std::isfinite(value)) return "-";
  const double scale = std::pow(10.0, -exponent);
  std::string text = format_value_error(value * scale, std::isfinite(error) ? error * scale : 0.0);
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] != ' ') out += text[i];  // "1.822 ± 0.011" -> "1.822±0.011"
  return out;
}

std::string scale_text(int exponent) { return exponent == 0 ? std::string() : fmt::format("1e{} ", exponent); }

std::string counters_text(const LabServiceRow& s) {
  std::string out;
  for (const auto& [name, value] : s.counters) {
    if (!out.empty()) out += ", ";
    out += fmt::format("{} {}", name, value);
  }
  return out.empty() ? "-" : out;
}


// Columns padded to their widest cell; the last column is not padded.
std::string format_columns(const std::vector<std::vector<std::string>>& rows, std::size_t width) {
  std::vector<std::size_t> widths;
  for (const auto& row : rows) {
    if (widths.size() < row.size()) widths.resize(row.size(), 0);
    for (std::size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], display_width(row[i]));
  }
  std::string out;
  for (const auto& row : rows) {
    std::string line;
    for (std::size_t i = 0; i < row.size(); ++i) {
      line += row[i];
      if (i + 1 < row.size()) line.append(widths[i] - display_width(row[i]) + 2, ' ');
    }
    out += cut_to_width(line, width) + '\n';
  }
  return out;
}

// The width format_columns gives rows: each column as wide as its widest cell, two spaces between.
std::size_t table_width(const std::vector<std::vector<std::string>>& rows) {
  std::vector<std::size_t> widths;
  for (const auto& row : rows) {
    if (widths.size() < row.size()) widths.resize(row.size(), 0);
    for (std::size_t i = 0; i < row.size(); ++i) widths[i] = std::max(widths[i], display_width(row[i]));
  }
  std::size_t total = 0;
  for (std::size_t i = 0; i < widths.size(); ++i) total += widths[i] + (i + 1 < widths.size() ? 2 : 0);
  return total;
}

}  // namespace

std::string cut_to_width(const std::string& line, std::size_t width) {
  return width == 0 ? line : line.substr(0, utf8_prefix_bytes(line, width));
}

namespace {

// Parameter k of a fit message: its value and total standard error (J's and K_b's uncertainty
// included when given, as a lab report quotes it), in the lab's units when asked; and the unit.
struct ParamValue {
  double value, error;
  std::string_view unit;
};
ParamValue param_value(const fit_t& msg, std::size_t k, bool lab_units) {
  ParamValue p{msg.param_value[k], msg.param_stderr[k], pretty_unit(msg.param_unit[k])};
  if (k < msg.param_bench_error.size() && msg.param_bench_error[k] > 0) p.error = std::hypot(p.error, msg.param_bench_error[k]);
  if (lab_units)
    if (auto lab = lab_unit_for(msg.param_unit[k])) {
      p.value *= lab->per_si;
      p.error *= lab->per_si;
      p.unit = lab->pretty;
    }
  return p;
}

// The parameter of that name of the named model (NaN when the message has none).
ParamValue model_param(const fit_t& msg, std::string_view model, std::string_view name, bool lab_units) {
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  const auto models = static_cast<std::size_t>(std::max(0, msg.nmodels));
  for (std::size_t m = 0; m < models && m < msg.model.size(); ++m) {
    if (msg.model[m] != model || (m < msg.converged.size() && !msg.converged[m])) continue;
    const auto params = static_cast<std::size_t>(std::max(0, msg.nparams));
    for (std::size_t k = 0; k < params && k < msg.param_name.size() && k < msg.param_model.size() &&
                            k < msg.param_value.size() && k < msg.param_stderr.size() && k < msg.param_unit.size();
         ++k)
      if (msg.param_model[k] == static_cast<std::int32_t>(m) && msg.param_name[k] == name)
        return param_value(msg, k, lab_units);
  }
  return {nan, nan, {}};
}

}  // namespace

std::string fit_coefficients_text(const fit_t& msg, bool lab_units, bool with_units) {
  if (msg.best.empty()) return {};
  const auto models = static_cast<std::size_t>(std::max(0, msg.nmodels));
  std::size_t best = models;
  for (std::size_t i = 0; i < models && i < msg.model.size(); ++i)
    if (msg.model[i] == msg.best) best = i;
  if (best == models) return {};
  std::string out;
  const auto params = static_cast<std::size_t>(std::max(0, msg.nparams));
  for (std::size_t k = 0; k < params && k < msg.param_name.size() && k < msg.param_model.size() &&
                          k < msg.param_value.size() && k < msg.param_stderr.size() && k < msg.param_unit.size();
       ++k) {
    if (msg.param_model[k] != static_cast<std::int32_t>(best) || !is_friction_coefficient(msg.param_name[k])) continue;
    const ParamValue p = param_value(msg, k, lab_units);
    if (!out.empty()) out += ", ";
    out += fmt::format("{} = {}", msg.param_name[k], format_value_error(p.value, p.error));
    if (with_units) out += fmt::format(" {}", p.unit);
  }
  return out;
}

LabTable::LabTable(LabTableOptions options) : opt_(options) {}

LabBenchRow& LabTable::row(std::string_view bench, std::int64_t now_us) {
  auto it = benches_.find(bench);
  if (it == benches_.end()) {
    if (opt_.max_benches > 0 && benches_.size() >= opt_.max_benches) {
      auto oldest = std::min_element(benches_.begin(), benches_.end(), [](const auto& a, const auto& b) {
        return a.second.last_message_us < b.second.last_message_us;
      });
      event(fmt::format("{}: forgotten (more than {} benches; heard last)", oldest->first, opt_.max_benches));
      benches_.erase(oldest);
      ++forgotten_rows_;
    }
    it = benches_.emplace(std::string(bench), LabBenchRow{}).first;
    it->second.bench = std::string(bench);
    it->second.stream.options = opt_.stream;
  }
  it->second.last_message_us = std::max(it->second.last_message_us, now_us);
  changed_ = true;
  return it->second;
}

void LabTable::event(std::string text) {
  events_.push_back(std::move(text));
  while (opt_.max_events > 0 && events_.size() > opt_.max_events) {
    events_.pop_front();
    ++dropped_events_;
  }
}

std::vector<std::string> LabTable::take_events() {
  std::vector<std::string> out(std::make_move_iterator(events_.begin()), std::make_move_iterator(events_.end()));
  events_.clear();
  return out;
}

// The fitter's rules (sample_stream.hpp): its words for a new source, two at once, a far jump.
struct LabTable::StreamSink {
  LabTable& table;
  LabBenchRow& r;
  std::int64_t now_us;
  void problem(SampleProblem kind, std::int64_t count, std::string text) {
    switch (kind) {
      case SampleProblem::samples_lost:
        ++r.seq_gaps;
        r.samples_missing += count;
        return;
      case SampleProblem::new_source:
        ++r.seq_restarts;
        table.event(fmt::format("{}: {}", r.bench, text));
        return;
      case SampleProblem::two_sources:
        r.two_sources = fmt::format("SPINDOWN.{}.SAMPLE {}", r.bench, text);
        r.other_source_us = now_us;
        table.event(r.two_sources);
        return;
      case SampleProblem::other_source:
        r.other_source_samples += count;
        r.other_source_us = now_us;
        return;
      case SampleProblem::jump:
        ++r.seq_jumps;
        table.event(fmt::format("{}: {}", r.bench, text));
        return;
      default: return;  // repeats, restarts, NaN…: the fitter's STATUS counts them
    }
  }
  void sample(std::int64_t, std::int64_t, double) { ++r.samples; }
};
void LabTable::tick(std::int64_t now_us) {
  for (auto& [id, r] : benches_)
    if (r.stream.waiting()) {
      r.stream.expire(now_us, StreamSink{*this, r, now_us});
      gap_event(r, now_us);
    }
}

void LabTable::on_samples(std::string_view bench, const samples_t& msg, std::int64_t now_us) {
  LabBenchRow& r = row(bench, now_us);
  if (msg.auth_key_id != 0) signed_traffic_ = true;
  const auto n = static_cast<std::size_t>(std::max<std::int32_t>(0, std::min<std::int32_t>(
                                              msg.n, static_cast<std::int32_t>(std::min(msg.device_time_us.size(),
                                                                                          msg.value.size())))));
  if (r.stream.take(msg, n, now_us, StreamSink{*this, r, now_us})) ++r.sample_messages;
  r.has_samples = true;
  r.last_sample_us = now_us;
  gap_event(r, now_us);
}

// "sequence gaps: …", at most every gap_event_every_s.
void LabTable::gap_event(LabBenchRow& r, std::int64_t now_us) {
  const double since = 1e-6 * double(now_us - r.last_gap_event_us);
  if (r.seq_gaps > r.gaps_at_last_event && (r.last_gap_event_us == 0 || since >= opt_.gap_event_every_s)) {
    event(fmt::format("{}: sequence gaps: {} so far, {} samples lost on the way to this listener", r.bench,
                      r.seq_gaps, r.samples_missing));
    r.last_gap_event_us = now_us;
    r.gaps_at_last_event = r.seq_gaps;
  }
}

void LabTable::on_config(std::string_view bench, const config_t&, std::int64_t now_us) {
  row(bench, now_us).has_config = true;
}

void LabTable::on_run(std::string_view bench, const run_t& msg, std::int64_t now_us) {
  LabBenchRow& r = row(bench, now_us);
  const bool news = !r.has_run || r.run != msg.run || r.run_state != msg.state;
  r.has_run = true;
  r.run = msg.run;
  r.run_state = msg.state;
  r.t_cut_s = msg.t_cut_s;
  r.t_stop_s = msg.t_stop_s;
  r.run_samples = msg.samples;
  r.run_partial = msg.lead_in == "none";
  r.last_run_us = std::max(r.last_run_us, now_us);
  if (!news) return;
  std::string text = fmt::format("{}: run {} {}", r.bench, msg.run, run_state_name(msg.state));
  switch (msg.state) {
    case run_t::STATE_COASTING:
      if (r.run_partial && std::isfinite(msg.t_cut_s))
        text += fmt::format(" (joined mid-coast at t = {:.2f} s: the cut was not seen, a partial run)", msg.t_cut_s);
      else if (std::isfinite(msg.t_cut_s))
        text += fmt::format(" (cut at t = {:.2f} s)", msg.t_cut_s);
      break;
    case run_t::STATE_STOPPED:
      if (std::isfinite(msg.t_stop_s) && std::isfinite(msg.t_cut_s))
        text += fmt::format(" (stop at t = {:.2f} s, {:.2f} s after the {}, {} samples)", msg.t_stop_s,
                            msg.t_stop_s - msg.t_cut_s, r.run_partial ? "first sample" : "cut", msg.samples);
      break;
    case run_t::STATE_ABANDONED:
      if (!msg.note.empty()) text += ": " + msg.note;
      break;
    default:
      break;
  }
  event(std::move(text));
}

void LabTable::on_fit(std::string_view bench, const fit_t& msg, std::int64_t now_us) {
  LabBenchRow& r = row(bench, now_us);
  r.has_fit = true;
  ++r.fits;
  r.fit_run = msg.run;
  r.fit_partial = msg.lead_in == "none";
  r.fit_end = msg.end;
  r.best = msg.best;
  r.coefficients = fit_coefficients_text(msg, opt_.lab_units, false);
  const ParamValue c3 = model_param(msg, "combined", "c3", opt_.lab_units), c4 = model_param(msg, "combined", "c4", opt_.lab_units);
  r.c3 = c3.value, r.c3_error = c3.error, r.c4 = c4.value, r.c4_error = c4.error;
  const std::string with_units = fit_coefficients_text(msg, opt_.lab_units, true);
  r.rmse = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < msg.model.size() && i < msg.rmse.size(); ++i)
    if (msg.model[i] == msg.best) r.rmse = msg.rmse[i];
  r.residual_unit = msg.residual_unit;
  r.bench_source = msg.bench_source;
  r.health = msg.verdict;
  r.health_reason = msg.verdict_reason;
  // Who published it: with signatures checked, the gate let only the lab's own through; without,
  // a signed FIT cannot be checked here, and one from a session no fitter heard on STATUS has is
  // not the lab fitter's (a forged FIT, or a fitter of another name).
  r.fit_doubt.clear();
  const auto session = static_cast<std::uint64_t>(msg.source_session);
  if (msg.auth_key_id != 0) signed_traffic_ = true;
  if (!opt_.signatures_checked && msg.auth_key_id != 0) {
    r.fit_doubt = "signed, signature not checked (watch --key)";
  } else if (!opt_.signatures_checked && !fitter_sessions_.empty() && session != 0 &&
             std::find(fitter_sessions_.begin(), fitter_sessions_.end(), session) == fitter_sessions_.end()) {
    r.fit_doubt = fmt::format("from {}, no fitter heard on STATUS: forged?", source_text(msg.source_host, session));
  }
  std::string text;
  if (msg.best.empty()) {
    text = fmt::format("{}: run {} fit: no model converged", r.bench, msg.run);
  } else {
    text = fmt::format("{}: run {} fit{}: best {}", r.bench, msg.run,
                       r.fit_partial ? " (partial: the cut was not seen, fitted from the first sample)" : "", msg.best);
    if (!with_units.empty()) text += ": " + with_units;
    if (std::isfinite(r.rmse)) text += fmt::format(", RMSE {:.3g} {}", r.rmse, r.residual_unit);
  }
  if (!msg.bench_source.empty() && msg.bench_source != "config") text += fmt::format(" [J/K_b: {}]", msg.bench_source);
  if (!msg.verdict.empty()) text += fmt::format("; health {}: {}", msg.verdict, msg.verdict_reason);
  if (!r.fit_doubt.empty()) text += fmt::format(" [NOT VERIFIED: {}]", r.fit_doubt);
  event(std::move(text));
}

void LabTable::on_status(std::string_view channel_id, const status_t& msg, std::int64_t now_us) {
  if (msg.service == "bridge") {
    LabBenchRow& r = row(channel_id, now_us);
    const std::string before = r.bridge_state;
    r.has_bridge = true;
    r.bridge_state = msg.state;
    r.lines_good = find_counter(msg, "lines_good").value_or(0);
    r.lines_bad = find_counter(msg, "lines_bad").value_or(0);
    r.rate_hz = find_gauge(msg, "rate_hz").value_or(0);
    if (!msg.last_error.empty() && msg.last_error != r.bridge_error)
      event(fmt::format("{}: bridge: {}", r.bench, msg.last_error));
    r.bridge_error = msg.last_error;
    if (before != msg.state) event(fmt::format("{}: bridge {}", r.bench, msg.state));
    return;
  }
  const std::string instance_name = msg.instance.empty() ? std::string(channel_id) : msg.instance;
  const std::string key = fmt::format("{}/{}", msg.service, instance_name);
  if (msg.service == "fitter" && msg.source_session != 0) {
    const auto session = static_cast<std::uint64_t>(msg.source_session);
    if (std::find(fitter_sessions_.begin(), fitter_sessions_.end(), session) == fitter_sessions_.end()) {
      if (fitter_sessions_.size() >= 64) fitter_sessions_.erase(fitter_sessions_.begin());
      fitter_sessions_.push_back(session);
    }
  }
  auto it = services_.find(key);
  if (it == services_.end()) {
    if (opt_.max_services > 0 && services_.size() >= opt_.max_services) {
      auto oldest = std::min_element(services_.begin(), services_.end(), [](const auto& a, const auto& b) {
        return a.second.last_message_us < b.second.last_message_us;
      });
      services_.erase(oldest);
      ++forgotten_rows_;
    }
    it = services_.emplace(key, LabServiceRow(msg.service, instance_name)).first;
    event(fmt::format("{} {} on {} (pid {}): {}", msg.service, msg.instance, msg.host, msg.pid, msg.state));
  }
  LabServiceRow& s = it->second;
  if (auto collision = s.instances.heard(msg, now_us)) {
    s.collision = *collision;
    event(*collision);
  }
  if (!s.state.empty() && s.state != msg.state)
    event(fmt::format("{} {}: {}", msg.service, msg.instance, msg.state));
  if (!msg.last_error.empty() && msg.last_error != s.last_error)
    event(fmt::format("{} {}: {}", msg.service, msg.instance, msg.last_error));
  s.service = msg.service;
  s.instance = msg.instance.empty() ? std::string(channel_id) : msg.instance;
  s.host = msg.host;
  s.pid = msg.pid;
  s.state = msg.state;
  s.uptime_s = msg.uptime_s;
  s.last_error = msg.last_error;
  s.last_message_us = std::max(s.last_message_us, now_us);
  if (msg.service == "fitter" && now_us >= last_fitter_us_) {
    last_fitter_us_ = now_us;
    fitter_stopping_ = msg.state == "stopping";
  }
  s.counters.clear();
  auto pick = [&](auto names) {
    for (std::string_view name : names)
      if (auto v = find_counter(msg, name)) s.counters.emplace_back(std::string(name), *v);
  };
  if (msg.service == "fitter") {
    pick(fitter_counters);
  } else if (msg.service == "logger") {
    pick(logger_counters);
  } else {
    for (std::size_t i = 0; i < msg.counter_name.size() && i < msg.counter_value.size() && i < other_counters_shown;
         ++i)
      s.counters.emplace_back(msg.counter_name[i], msg.counter_value[i]);
  }
  changed_ = true;
}

void LabTable::on_refused(const GateResult& g, std::int64_t now_us, std::string_view bench) {
  if (!bench.empty() && g.verdict != GateVerdict::other_lab) {
    LabBenchRow& r = row(bench, now_us);
    r.refused = g.text;
    r.refused_kind = gate_verdict_name(g.verdict);
    r.refused_us = now_us;
  }
  ++refused_;
  const std::string kind(gate_verdict_name(g.verdict));
  ++refused_by_kind_[kind];
  // The first of each kind on each channel is an event (bounded: a flood of channels stops adding).
  const std::string where = kind + " " + g.text.substr(0, g.text.find(':'));
  if (refused_said_.size() < 256 && refused_said_.insert(where).second) event("not shown: " + g.text);
  last_refused_ = g.text;
  changed_ = true;
}

void LabTable::on_bad_message(std::string text, std::int64_t) {
  ++bad_messages_;
  if (bad_messages_ == 1) event(text);
  last_bad_message_ = std::move(text);
  changed_ = true;
}

bool LabTable::run_unfollowed(const LabBenchRow& r, std::int64_t now_us) const {
  if (!r.has_run || (r.run_state != run_t::STATE_COASTING && r.run_state != run_t::STATE_STOPPED)) return false;
  const auto lost_us = static_cast<std::int64_t>(opt_.fitter_lost_s * 1e6);
  if (now_us - r.last_run_us < lost_us) return false;
  // A stopped run is final once its FIT came (the fit's run is this run).
  if (r.run_state == run_t::STATE_STOPPED && r.has_fit && r.fit_run == r.run) return false;
  return fitter_stopping_ || now_us - last_fitter_us_ >= lost_us;
}

bool LabTable::refused_now(const LabBenchRow& r, std::int64_t now_us) const {
  const auto stale_us = static_cast<std::int64_t>(opt_.stale_s * 1e6);
  return r.refused_us > 0 && now_us - r.refused_us <= stale_us &&
         (r.last_sample_us == 0 || now_us - r.last_sample_us > stale_us);
}

bool LabTable::two_sources_now(const LabBenchRow& r, std::int64_t now_us) const {
  return !r.two_sources.empty() && now_us - r.other_source_us <= static_cast<std::int64_t>(opt_.stale_s * 1e6);
}

std::string LabTable::bench_table(std::int64_t now_us, std::size_t width) const {
  if (benches_.empty()) return {};
  const int e3 = column_exponent(benches_, &LabBenchRow::c3, opt_.lab_units);
  const int e4 = column_exponent(benches_, &LabBenchRow::c4, opt_.lab_units);
  // The columns in their order: header, short header, the order they are dropped in when the
  // width asks (0: never; the run, the coefficients and the verdict are what a row is for), and
  // the cell (full or short).
  struct Column {
    std::string head, short_head;
    int drop;
    std::function<std::string(const LabBenchRow&, bool)> cell;
  };
  const std::string c3_unit = opt_.lab_units ? "g·cm²·s⁻¹" : "N·m·s/rad", c4_unit = opt_.lab_units ? "g·cm²·rad·s⁻²" : "N·m";
  const std::vector<Column> columns{
      {"BENCH", "BENCH", 0, [](const LabBenchRow& r, bool) { return r.bench; }},
      {"RUN", "RUN", 0,
       [&](const LabBenchRow& r, bool brief) {
         if (refused_now(r, now_us)) return brief ? std::string("REFUSED") : "REFUSED: " + r.refused_kind;
         const bool unfollowed = run_unfollowed(r, now_us);
         return brief ? run_short(r, unfollowed) : run_state_text(r, unfollowed, now_us);
       }},
      {"AGE", "AGE", 4,
       [&](const LabBenchRow& r, bool) { return age_text(r.last_message_us, now_us, opt_.stale_s); }},
      {"BRIDGE (lines ok/bad, rate)", "BRIDGE", 1,
       [&](const LabBenchRow& r, bool brief) {
         const bool two = two_sources_now(r, now_us);
         return brief ? bridge_short(r) + (two ? " 2 SOURCES" : "") : bridge_text(r) + (two ? " TWO SOURCES" : "");
       }},
      {"SEQ GAPS", "GAPS", 2,
       [](const LabBenchRow& r, bool brief) {
         return brief && r.has_samples ? fmt::format("{}", r.seq_gaps) : gaps_text(r);
       }},
      {"LAST FIT (best model)", "FIT", 5, [](const LabBenchRow& r, bool brief) { return brief ? fit_short(r) : fit_text(r); }},
      {fmt::format("c3 ({}{})", scale_text(e3), c3_unit), "c3", 0,
       [e3](const LabBenchRow& r, bool) { return r.has_fit ? coefficient_cell(r.c3, r.c3_error, e3) : "-"; }},
      {fmt::format("c4 ({}{})", scale_text(e4), c4_unit), "c4", 0,
       [e4](const LabBenchRow& r, bool) { return r.has_fit ? coefficient_cell(r.c4, r.c4_error, e4) : "-"; }},
      {"RMSE", "RMSE", 3, [](const LabBenchRow& r, bool) { return rmse_text(r); }},
      {"HEALTH", "HEALTH", 0, [](const LabBenchRow& r, bool) { return health_text(r); }},
  };
  // Full headers and cells; short headers; short cells; then columns dropped one by one.
  const auto table = [&](bool short_heads, bool short_cells, int dropped) {
    std::vector<std::vector<std::string>> rows(1);
    for (const auto& c : columns)
      if (c.drop == 0 || c.drop > dropped) rows[0].push_back(short_heads ? c.short_head : c.head);
    for (const auto& [id, r] : benches_) {
      rows.emplace_back();
      for (const auto& c : columns)
        if (c.drop == 0 || c.drop > dropped) rows.back().push_back(c.cell(r, short_cells));
    }
    return rows;
  };
  const auto fits = [&](const std::vector<std::vector<std::string>>& rows) {
    return width == 0 || table_width(rows) <= width;
  };
  std::vector<std::vector<std::string>> rows = table(false, false, 0);
  const int most_dropped = 5;
  std::string dropped_note;
  if (!fits(rows)) rows = table(true, false, 0);
  if (!fits(rows)) rows = table(true, true, 0);
  for (int d = 1; d <= most_dropped && !fits(rows); ++d) {
    rows = table(true, true, d);
    for (const auto& c : columns)
      if (c.drop == d) dropped_note += (dropped_note.empty() ? "" : ", ") + c.short_head;
  }
  std::string out = format_columns(rows, width);
  // What the cells mean: the coefficients' scale and units, the marks, what the width left out.
  std::string units = fmt::format("c3 in {}{}, c4 in {}{} (combined model, ± total error)",
                                  scale_text(e3), c3_unit, scale_text(e4), c4_unit);
  out += cut_to_width(units, width) + '\n';
  if (!dropped_note.empty())
    out += cut_to_width(fmt::format("not shown at this width: {} (wider, or --plain)", dropped_note), width) + '\n';
  return out;
}

std::string LabTable::render(std::int64_t now_us, std::size_t width) const {
  std::string out;
  const std::time_t now_s = static_cast<std::time_t>(now_us / 1000000);
  std::tm local{};
  ::localtime_r(&now_s, &local);
  out += cut_to_width(fmt::format("spindown watch  {:02}:{:02}:{:02}  {} bench{}, {} service{}", local.tm_hour,
                                  local.tm_min, local.tm_sec, benches_.size(), benches_.size() == 1 ? "" : "es",
                                  services_.size(), services_.size() == 1 ? "" : "s"),
                      width) +
         '\n';
  if (signed_traffic_ && !opt_.signatures_checked)
    out += cut_to_width("signed lab traffic, signatures NOT checked: run with --key FILE (the lab key) to see only the "
                        "lab's own messages",
                        width) +
           '\n';
  out += bench_table(now_us, width);
  // A second source on a bench's SAMPLE channel heard lately, and a fit watch cannot vouch for:
  // marked in the row and said under the table.
  for (const auto& [id, r] : benches_) {
    if (two_sources_now(r, now_us)) out += cut_to_width("  " + r.two_sources, width) + '\n';
    if (refused_now(r, now_us)) out += cut_to_width("  " + r.bench + ": its samples are refused: " + r.refused, width) + '\n';
    if (!r.fit_doubt.empty())
      out += cut_to_width(fmt::format("  {}: run {} fit NOT VERIFIED: {}", id, r.fit_run, r.fit_doubt), width) + '\n';
  }
  if (benches_.empty()) out += "(no bench heard yet)\n";
  if (!services_.empty()) {
    std::vector<std::vector<std::string>> srows;
    srows.push_back({"SERVICE", "STATE", "HOST/PID", "COUNTERS", "AGE"});
    for (const auto& [key, s] : services_) {
      const std::size_t alive = s.instances.alive(now_us).size();
      srows.push_back({s.service + " " + s.instance, alive > 1 ? fmt::format("{} INSTANCES!", alive) : s.state,
                       fmt::format("{}/{}", s.host, s.pid), counters_text(s),
                       age_text(s.last_message_us, now_us, opt_.stale_s)});
    }
    out += '\n' + format_columns(srows, width);
    for (const auto& [key, s] : services_) {
      if (s.instances.alive(now_us).size() > 1 && !s.collision.empty())
        out += cut_to_width("  " + s.collision, width) + '\n';
      if (!s.last_error.empty())
        out += cut_to_width(fmt::format("  {} {}: last error: {}", s.service, s.instance, s.last_error), width) + '\n';
    }
  }
  if (bad_messages_ > 0)
    out += cut_to_width(fmt::format("{} undecodable message{}; last: {}", bad_messages_, bad_messages_ == 1 ? "" : "s",
                                    last_bad_message_),
                        width) +
           '\n';
  if (refused_ > 0) {
    std::string kinds;
    for (const auto& [kind, count] : refused_by_kind_) kinds += fmt::format("{}{} {}", kinds.empty() ? "" : ", ", count, kind);
    out += cut_to_width(fmt::format("{} message{} not shown ({}); last: {}", refused_, refused_ == 1 ? "" : "s", kinds,
                                    last_refused_),
                        width) +
           '\n';
  }
  return out;
}

const LabBenchRow* LabTable::bench(std::string_view id) const {
  auto it = benches_.find(id);
  return it == benches_.end() ? nullptr : &it->second;
}

std::vector<std::string> LabTable::bench_ids() const {
  std::vector<std::string> ids;
  for (const auto& [id, r] : benches_) ids.push_back(id);
  return ids;
}

const LabServiceRow* LabTable::service(std::string_view service, std::string_view instance) const {
  auto it = services_.find(fmt::format("{}/{}", service, instance));
  return it == services_.end() ? nullptr : &it->second;
}

std::vector<const LabServiceRow*> LabTable::services() const {
  std::vector<const LabServiceRow*> out;
  for (const auto& [key, s] : services_) out.push_back(&s);
  return out;
}

}  // namespace spindown
