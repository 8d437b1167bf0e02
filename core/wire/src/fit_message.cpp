#include "spindown/fit_message.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>

#include "spindown/fail_why.hpp"
#include "spindown/quantity.hpp"

namespace spindown {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

fit_t to_fit_message(const RunFit& fit, const FitProvenance& about, std::int64_t utime) {
  fit_t m{};
  m.utime = utime;
  m.bench = about.bench;
  m.run = fit.run.number;
  m.t_cut_s = fit.run.t_cut_s;
  m.t_stop_s = fit.run.stopped ? fit.run.t_stop_s : nan;
  m.samples = static_cast<std::int32_t>(fit.run.end_index > fit.run.cut_index ? fit.run.end_index - fit.run.cut_index
                                                                               : 0);
  m.inertia_kg_m2 = fit.bench.inertia_kg_m2;
  m.kb_v_s_per_rad = fit.bench.kb_v_s_per_rad;
  m.inertia_rel_error = fit.bench.inertia_rel_error;
  m.kb_rel_error = fit.bench.kb_rel_error;
  m.bench_source = about.bench_source;
  m.zero_level = fit.run.zero_level;
  m.residual_unit = std::string(quantity_unit(fit.quantity));

  m.nmodels = static_cast<std::int32_t>(fit.models.size());
  m.nparams = 0;
  for (std::size_t i = 0; i < fit.models.size(); ++i) {
    const ModelFit& f = fit.models[i];
    m.model.emplace_back(model_name(f.kind));
    m.rmse.push_back(f.rmse);
    m.r2.push_back(f.r2);
    m.aic.push_back(f.aic);
    m.bic.push_back(f.bic);
    m.t_stop_pred_s.push_back(f.t_stop_pred_s);
    m.converged.push_back(f.converged);
    m.model_samples.push_back(static_cast<std::int32_t>(f.n));
    m.model_message.push_back(f.message);
    for (const Parameter& p : f.params) {
      m.param_model.push_back(static_cast<std::int32_t>(i));
      m.param_name.push_back(p.name);
      m.param_value.push_back(p.value);
      m.param_stderr.push_back(p.std_error);
      m.param_unit.push_back(p.unit);
      m.param_bench_error.push_back(p.bench_error);
      ++m.nparams;
    }
  }
  m.best = fit.best;
  m.best_reason = fit.best_reason;
  m.verdict = "";  // not assessed: the fitter has no bench file for this bench
  m.verdict_reason = "";
  m.health_reference = false;
  m.nfindings = 0;
  if (about.health) {
    const HealthVerdict& h = *about.health;
    m.verdict = std::string(health_level_name(h.level));
    m.verdict_reason = h.reason;
    m.health_reference = h.has_reference;
    for (const HealthFinding& f : h.findings) {
      m.finding_what.push_back(f.what);
      m.finding_level.emplace_back(health_level_name(f.level));
      m.finding_reason.push_back(f.reason);
      m.finding_value.push_back(f.value);
      m.finding_stderr.push_back(f.std_error);
      m.finding_reference.push_back(f.reference);
      m.finding_reference_stderr.push_back(f.reference_std_error);
      m.finding_reference_name.push_back(f.reference_name);
      m.finding_ratio.push_back(f.ratio);
      m.finding_ratio_stderr.push_back(f.ratio_std_error);
      m.finding_unit.push_back(f.unit);
      ++m.nfindings;
    }
  }
  m.latency_s = about.latency_s;
  m.inertia_source = fit.bench.inertia_source;
  m.kb_source = fit.bench.kb_source;
  m.lead_in = fit.run.lead_in;
  m.noise_level = fit.run.noise_level;
  m.period_s = fit.run.period_s;
  m.first_seq = about.first_seq;
  m.t_end_s = fit.run.t_end_s;
  m.end = end_name(fit.run.end);
  m.last_seq = about.last_seq;
  m.ndoubts = static_cast<std::int32_t>(fit.doubts.size());
  m.doubts = fit.doubts;
  m.reading_step = fit.reading_step;
  m.reading_noise = fit.reading_noise;
  m.ncorrelations = 0;
  for (std::size_t i = 0; i < fit.models.size(); ++i) {
    const ModelFit& f = fit.models[i];
    m.model_reduced_chi2.push_back(f.reduced_chi2);
    const std::size_t k = f.correlated.size();
    if (f.correlation.size() != k * k) continue;
    for (std::size_t a = 0; a < k; ++a)
      for (std::size_t b = a + 1; b < k; ++b) {
        m.corr_model.push_back(static_cast<std::int32_t>(i));
        m.corr_a.push_back(f.correlated[a]);
        m.corr_b.push_back(f.correlated[b]);
        m.corr_value.push_back(f.correlation[a * k + b]);
        ++m.ncorrelations;
      }
  }
  m.bridge_host = about.bridge_host;
  m.bridge_session = static_cast<std::int64_t>(about.bridge_session);
  return m;
}

std::optional<RunFit> from_fit_message(const fit_t& m, std::string* why) {
  const auto nm = static_cast<std::size_t>(std::max(m.nmodels, 0));
  const auto np = static_cast<std::size_t>(std::max(m.nparams, 0));
  if (m.nmodels < 0 || m.nparams < 0 || m.model.size() != nm || m.rmse.size() != nm || m.r2.size() != nm ||
      m.aic.size() != nm || m.bic.size() != nm || m.t_stop_pred_s.size() != nm || m.converged.size() != nm ||
      m.model_samples.size() != nm || m.model_message.size() != nm || m.param_model.size() != np ||
      m.param_name.size() != np || m.param_value.size() != np || m.param_stderr.size() != np ||
      m.param_unit.size() != np || m.param_bench_error.size() != np) {
    fail_why(why, fmt::format("FIT of bench {} run {}: array sizes do not match nmodels {} / nparams {}", m.bench, m.run,
                              m.nmodels, m.nparams));
    return std::nullopt;
  }
  RunFit fit;
  fit.run.number = m.run;
  fit.run.t_cut_s = m.t_cut_s;
  fit.run.stopped = std::isfinite(m.t_stop_s);
  fit.run.t_stop_s = m.t_stop_s;
  fit.run.t_end_s = m.t_end_s;
  fit.run.end = end_from_name(m.end);
  fit.run.cut_index = 0;
  fit.run.end_index = static_cast<std::size_t>(std::max(m.samples, 0));
  fit.run.stop_index = fit.run.end_index;
  fit.run.zero_level = m.zero_level;
  fit.run.noise_level = m.noise_level;
  fit.run.lead_in = m.lead_in;
  fit.run.period_s = m.period_s;
  fit.bench.inertia_kg_m2 = m.inertia_kg_m2;
  fit.bench.kb_v_s_per_rad = m.kb_v_s_per_rad;
  fit.bench.inertia_source = m.inertia_source;
  fit.bench.kb_source = m.kb_source;
  fit.bench.inertia_rel_error = m.inertia_rel_error;
  fit.bench.kb_rel_error = m.kb_rel_error;
  const auto q = parse_quantity(m.residual_unit);
  if (!q) {
    fail_why(why, fmt::format("FIT of bench {} run {}: unknown residual unit '{}'", m.bench, m.run, m.residual_unit));
    return std::nullopt;
  }
  fit.quantity = *q;
  for (std::size_t i = 0; i < nm; ++i) {
    const auto kind = parse_model(m.model[i]);
    if (!kind) {
      fail_why(why, fmt::format("FIT of bench {} run {}: unknown model '{}'", m.bench, m.run, m.model[i]));
      return std::nullopt;
    }
    ModelFit f;
    f.kind = *kind;
    f.rmse = m.rmse[i];
    f.r2 = m.r2[i];
    f.aic = m.aic[i];
    f.bic = m.bic[i];
    f.t_stop_pred_s = m.t_stop_pred_s[i];
    f.converged = m.converged[i];
    f.n = static_cast<std::size_t>(std::max(m.model_samples[i], 0));
    f.message = m.model_message[i];
    fit.models.push_back(std::move(f));
  }
  for (std::size_t k = 0; k < np; ++k) {
    const std::int32_t i = m.param_model[k];
    if (i < 0 || static_cast<std::size_t>(i) >= nm) {
      fail_why(why, fmt::format("FIT of bench {} run {}: parameter {} belongs to model {} of {}", m.bench, m.run,
                                m.param_name[k], i, nm));
      return std::nullopt;
    }
    ModelFit& f = fit.models[static_cast<std::size_t>(i)];
    f.params.push_back({m.param_name[k], m.param_value[k], m.param_stderr[k], m.param_unit[k], m.param_bench_error[k]});
    if (m.param_name[k] == "omega0") f.omega0 = m.param_value[k];
  }
  // Each model's speed law (ModelFit::omega_at: c/J of its viscous and Coulomb terms).
  const double inertia = fit.bench.inertia_kg_m2;
  for (ModelFit& f : fit.models) {
    const auto per_j = [&](std::string_view name) {
      const Parameter* p = f.param(name);
      return p && inertia > 0 ? p->value / inertia : 0.0;
    };
    f.rate = per_j(f.kind == ModelKind::combined ? "c3" : "c1");
    f.decel = per_j(f.kind == ModelKind::combined ? "c4" : "c2");
  }
  fit.best = m.best;
  fit.best_reason = m.best_reason;
  const auto nd = static_cast<std::size_t>(std::max(m.ndoubts, 0));
  const auto nc = static_cast<std::size_t>(std::max(m.ncorrelations, 0));
  if (m.doubts.size() != nd || m.model_reduced_chi2.size() != nm || m.corr_model.size() != nc ||
      m.corr_a.size() != nc || m.corr_b.size() != nc || m.corr_value.size() != nc) {
    fail_why(why, fmt::format("FIT of bench {} run {}: array sizes do not match ndoubts {} / ncorrelations {}", m.bench,
                              m.run, m.ndoubts, m.ncorrelations));
    return std::nullopt;
  }
  fit.doubts = m.doubts;
  fit.reading_step = m.reading_step;
  fit.reading_noise = m.reading_noise;
  for (std::size_t i = 0; i < nm; ++i) fit.models[i].reduced_chi2 = m.model_reduced_chi2[i];
  // Each model's correlation matrix again, from its pairs (omega0 first, as fit_run orders them).
  for (std::size_t c = 0; c < nc; ++c) {
    const std::int32_t i = m.corr_model[c];
    if (i < 0 || static_cast<std::size_t>(i) >= nm) {
      fail_why(why, fmt::format("FIT of bench {} run {}: correlation {} belongs to model {} of {}", m.bench, m.run, c, i,
                                nm));
      return std::nullopt;
    }
    auto& names = fit.models[static_cast<std::size_t>(i)].correlated;
    for (const std::string* n : {&m.corr_a[c], &m.corr_b[c]})
      if (std::find(names.begin(), names.end(), *n) == names.end()) names.push_back(*n);
  }
  for (std::size_t i = 0; i < nm; ++i) {
    ModelFit& f = fit.models[i];
    const std::size_t k = f.correlated.size();
    f.correlation.assign(k * k, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t a = 0; a < k; ++a) f.correlation[a * k + a] = 1.0;
  }
  for (std::size_t c = 0; c < nc; ++c) {
    ModelFit& f = fit.models[static_cast<std::size_t>(m.corr_model[c])];
    const auto index = [&](const std::string& n) {
      return static_cast<std::size_t>(std::find(f.correlated.begin(), f.correlated.end(), n) - f.correlated.begin());
    };
    const std::size_t k = f.correlated.size(), a = index(m.corr_a[c]), b = index(m.corr_b[c]);
    f.correlation[a * k + b] = f.correlation[b * k + a] = m.corr_value[c];
  }
  return fit;
}

std::optional<HealthVerdict> health_from_fit_message(const fit_t& m, std::string* why) {
  if (m.verdict.empty()) return std::nullopt;
  const auto n = static_cast<std::size_t>(std::max(m.nfindings, 0));
  if (m.nfindings < 0 || m.finding_what.size() != n || m.finding_level.size() != n || m.finding_reason.size() != n ||
      m.finding_value.size() != n || m.finding_stderr.size() != n || m.finding_reference.size() != n ||
      m.finding_reference_stderr.size() != n || m.finding_reference_name.size() != n || m.finding_ratio.size() != n ||
      m.finding_ratio_stderr.size() != n || m.finding_unit.size() != n) {
    fail_why(why, fmt::format("FIT of bench {} run {}: health finding arrays do not match nfindings {}", m.bench, m.run,
                              m.nfindings));
    return std::nullopt;
  }
  const auto level = parse_health_level(m.verdict);
  if (!level) {
    fail_why(why, fmt::format("FIT of bench {} run {}: unknown health verdict '{}'", m.bench, m.run, m.verdict));
    return std::nullopt;
  }
  HealthVerdict v;
  v.level = *level;
  v.reason = m.verdict_reason;
  v.has_reference = m.health_reference;
  for (std::size_t i = 0; i < n; ++i) {
    const auto fl = parse_health_level(m.finding_level[i]);
    if (!fl) {
      fail_why(why, fmt::format("FIT of bench {} run {}: unknown health level '{}' of finding '{}'", m.bench, m.run,
                                m.finding_level[i], m.finding_what[i]));
      return std::nullopt;
    }
    HealthFinding f;
    f.what = m.finding_what[i];
    f.level = *fl;
    f.reason = m.finding_reason[i];
    f.value = m.finding_value[i];
    f.std_error = m.finding_stderr[i];
    f.reference = m.finding_reference[i];
    f.reference_std_error = m.finding_reference_stderr[i];
    f.reference_name = m.finding_reference_name[i];
    f.ratio = m.finding_ratio[i];
    f.ratio_std_error = m.finding_ratio_stderr[i];
    f.unit = m.finding_unit[i];
    v.findings.push_back(std::move(f));
  }
  return v;
}

std::optional<Json> fit_message_json(const fit_t& msg, const ReportOptions& opt, std::string* why) {
  auto fit = from_fit_message(msg, why);
  if (!fit) return std::nullopt;
  Json j = tagged_run_fit_json(*fit, {msg.bench, msg.first_seq, msg.last_seq}, opt);
  if (!msg.verdict.empty()) {
    auto health = health_from_fit_message(msg, why);
    if (!health) return std::nullopt;
    j["health"] = health_json(*health);
  }
  return j;
}

run_t to_run_message(std::string_view bench, const Run& run, std::int8_t state, std::int64_t first_seq,
                     std::int64_t last_seq, std::int32_t samples, std::string note, std::int64_t utime) {
  run_t m{};
  m.utime = utime;
  m.bench = std::string(bench);
  m.run = run.number;
  m.state = state;
  m.t_cut_s = run.t_cut_s;
  m.t_stop_s = run.stopped ? run.t_stop_s : nan;
  m.first_seq = first_seq;
  m.last_seq = last_seq;
  m.samples = samples;
  m.note = std::move(note);
  m.lead_in = run.lead_in;
  return m;
}

std::string_view run_state_name(std::int8_t state) {
  switch (state) {
    case run_t::STATE_POWERED: return "powered";
    case run_t::STATE_COASTING: return "coasting";
    case run_t::STATE_STOPPED: return "stopped";
    case run_t::STATE_ABANDONED: return "abandoned";
    default: return "unknown";
  }
}

Json without_timing_fields(Json j) {
  if (j.is_object()) {
    j.erase("latency_s");
    j.erase("utime");
    for (auto& [key, value] : j.items()) value = without_timing_fields(std::move(value));
  } else if (j.is_array()) {
    for (auto& value : j) value = without_timing_fields(std::move(value));
  }
  return j;
}

}  // namespace spindown
