#include "spindown/explain.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <limits>

#include "spindown/effect_simulator.hpp"
#include "spindown/reading_noise.hpp"

namespace spindown {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

std::vector<double> residual_of(std::span<const double> y, const EffectFit& f) {
  std::vector<double> r(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) r[i] = y[i] - f.simulated[i];
  return r;
}

// How much systematic disagreement a residual carries: Σ z² over the bins beyond what noise
// alone gives (K bins → K), judged with a fixed bin noise so models compare fairly.
double systematic_mass(const ResidualBins& b, double bin_se) {
  double s = 0;
  for (double m : b.mean) s += (m / bin_se) * (m / bin_se);
  return std::max(0.0, s - static_cast<double>(b.mean.size()));
}

// A chi-square excess beyond 3 standard deviations (2K variance) is not noise.
bool mass_significant(double mass, std::size_t bins) { return mass > 3.0 * std::sqrt(2.0 * static_cast<double>(bins)); }

// Model speed (rad/s) at each sample, sensor terms removed.
std::vector<double> model_speed(const EffectFit& f, std::span<const double> tau, double k) {
  if (f.theta.empty() || !std::isfinite(f.theta[0])) return std::vector<double>(tau.size(), nan);
  const EffectSimulator sim(f.effects, k);
  return sim.omega(f.theta, tau);
}

std::vector<Disagreement> locate(const ResidualBins& b, double bin_se, double z_thr, std::span<const double> tau,
                                 std::span<const double> residual, const std::vector<double>& speed, double t_cut) {
  std::vector<Disagreement> out;
  const std::size_t nb = b.mean.size();
  std::size_t k = 0;
  while (k < nb) {
    const double z = b.mean[k] / bin_se;
    if (std::abs(z) <= z_thr) {
      ++k;
      continue;
    }
    std::size_t e = k + 1;
    while (e < nb && std::abs(b.mean[e] / bin_se) > z_thr && (b.mean[e] > 0) == (z > 0)) ++e;
    const std::size_t i0 = b.first[k];
    const std::size_t i1 = e < nb ? b.first[e] : tau.size();  // one past the last sample
    Disagreement d;
    d.tau_from_s = tau[i0];
    d.tau_to_s = tau[i1 - 1];
    d.t_from_s = d.tau_from_s + t_cut;
    d.t_to_s = d.tau_to_s + t_cut;
    d.omega_from = speed[i0];
    d.omega_to = speed[i1 - 1];
    double sum = 0;
    for (std::size_t i = i0; i < i1; ++i) sum += residual[i];
    d.mean_residual = sum / static_cast<double>(i1 - i0);
    for (std::size_t j = k; j < e; ++j)
      if (std::abs(b.mean[j]) > std::abs(d.peak_residual)) d.peak_residual = b.mean[j];
    d.z = d.peak_residual / bin_se;
    out.push_back(d);
    k = e;
  }
  // Keep the few that carry most of the disagreement, in time order.
  constexpr std::size_t keep = 6;
  if (out.size() > keep) {
    auto weight = [](const Disagreement& d) { return std::abs(d.mean_residual) * (d.tau_to_s - d.tau_from_s + 1e-3); };
    std::vector<Disagreement> sorted = out;
    std::sort(sorted.begin(), sorted.end(), [&](const auto& a, const auto& c) { return weight(a) > weight(c); });
    sorted.resize(keep);
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& c) { return a.tau_from_s < c.tau_from_s; });
    out = sorted;
  }
  return out;
}

// The reading's resolution: the smallest step between distinct values (2-decimal prints:
// 0.01 V). Near it, rounding is a deterministic, speed-dependent distortion no effect explains.
double reading_quantum(std::span<const double> y) {
  std::vector<double> v(y.begin(), y.end());
  std::sort(v.begin(), v.end());
  double q = std::numeric_limits<double>::infinity();
  for (std::size_t i = 1; i < v.size(); ++i) {
    const double d = v[i] - v[i - 1];
    if (d > 1e-9 * (std::abs(v[i]) + 1e-12)) q = std::min(q, d);
  }
  return std::isfinite(q) ? q : 0.0;
}

// Largest change (bin means) a candidate makes to the current model's simulation.
double largest_change(const EffectFit& a, const EffectFit& b, std::size_t m) {
  double worst = 0;
  for (std::size_t i = 0; i < a.simulated.size(); i += m) {
    const std::size_t e = std::min(i + m, a.simulated.size());
    double s = 0;
    for (std::size_t j = i; j < e; ++j) s += b.simulated[j] - a.simulated[j];
    worst = std::max(worst, std::abs(s) / static_cast<double>(e - i));
  }
  return worst;
}

bool contains(const std::vector<const Effect*>& v, const Effect* e) {
  return std::find(v.begin(), v.end(), e) != v.end();
}

// The model plus one effect, in library order (so names and parameters read the same way).
std::vector<const Effect*> with_effect(const std::vector<const Effect*>& model, const Effect* e) {
  std::vector<const Effect*> out;
  for (const Effect& lib : effect_library())
    if (&lib == e || contains(model, &lib)) out.push_back(&lib);
  return out;
}

}  // namespace

bool ExplainOptions::is_valid(std::string* why) const {
  if (!bench.is_valid(why)) return false;
  auto fail = [&](std::string m) {
    if (why) *why = std::move(m);
    return false;
  };
  if (base.empty()) return fail("the base model needs at least one effect");
  bool torque = false;
  for (const Effect* e : base) {
    if (!e) return fail("unknown effect in the base model");
    torque = torque || e->kind == EffectKind::torque;
  }
  if (!torque) return fail("the base model needs a friction term (viscous, coulomb, …)");
  for (const Effect* e : candidates)
    if (!e) return fail("unknown candidate effect");
  if (!(min_delta_bic >= 0) || !(bin_s > 0) || !(systematic_z > 0) || max_steps < 0)
    return fail("thresholds must be positive");
  return true;
}

double white_noise(std::span<const double> y) { return reading_noise_sigma(y); }

double ExplainResult::bin_noise_white() const {
  return bin_samples > 0 ? reading_noise / std::sqrt(static_cast<double>(bin_samples)) : reading_noise;
}

std::string effect_term(const Effect& effect, const EffectFit& fit) {
  const auto has = [&](std::string_view name) { return fit.param(name) != nullptr; };
  const std::string coulomb = has("c4") ? "c4" : has("c2") ? "c2" : "";
  if (effect.name == "viscous") return fmt::format("T = {}·ω", has("c3") ? "c3" : "c1");
  if (effect.name == "coulomb") return fmt::format("T = {}", coulomb.empty() ? "c2" : coulomb);
  if (effect.name == "stribeck")
    return coulomb.empty() ? "T = c_s·exp(−(ω/ω_s)²)" : fmt::format("T = (c_s − {})·exp(−(ω/ω_s)²)", coulomb);
  return std::string(effect.term);
}

namespace {

// Stribeck friction whose speed scale is a third of the top speed or more.
bool broad_stribeck(const Effect& effect, const EffectFit& fit, double top_speed) {
  const Parameter* ws = fit.param("w_s");
  return effect.name == "stribeck" && ws && std::isfinite(ws->value) && top_speed > 0 && ws->value >= top_speed / 3;
}

}  // namespace

std::string effect_meaning(const Effect& effect, const EffectFit& fit, double top_speed) {
  const Parameter* ws = fit.param("w_s");
  if (broad_stribeck(effect, fit, top_speed)) {
    // exp(−(ω/ω_s)²) halves at ω_s·√ln 2.
    const double half = ws->value * std::sqrt(std::log(2.0));
    return fmt::format("friction that falls with speed over much of the coast, not only near standstill: the extra "
                       "friction above Coulomb's halves by {:.3g} rad/s, {:.0f} % of the top speed {:.3g} rad/s "
                       "(ω_s = {:.3g} rad/s) - far wider than a lubricant film breaking down near standstill",
                       half, 100 * half / top_speed, top_speed, ws->value);
  }
  if (effect.name == "stribeck" && ws && std::isfinite(ws->value) && top_speed > 0)
    return fmt::format("{} (ω_s = {:.3g} rad/s, {:.0f} % of the top speed {:.3g} rad/s)", effect.meaning, ws->value,
                       100 * ws->value / top_speed, top_speed);
  return std::string(effect.meaning);
}

std::string effect_signature(const Effect& effect, const EffectFit& fit, double top_speed) {
  if (broad_stribeck(effect, fit, top_speed))
    return "the coast decelerates harder as it slows over much of its length, more than viscous and Coulomb friction "
           "allow: residuals of one sign early and late, of the other in between";
  return std::string(effect.signature);
}

ExplainResult explain_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
                          const ExplainOptions& opt) {
  ExplainResult out;
  out.run = run;
  out.bench = opt.bench;
  out.quantity = q;
  out.unit = std::string(quantity_unit(q));
  std::string why;
  if (!opt.is_valid(&why)) {
    out.message = why;
    return out;
  }
  // spindown fit's samples (fit.cpp): the window less its outliers.
  const std::size_t begin = std::min(run.cut_index, t_s.size());
  const std::size_t end = std::clamp(run.end_index, begin, std::min(t_s.size(), value.size()));
  const std::size_t stop = std::clamp(run.stop_index, begin, end);
  out.zero_level = std::isfinite(run.zero_level) ? run.zero_level : 0.0;
  std::size_t moving = 0;  // samples kept before the stop
  for (std::size_t i = begin; i < end; ++i) {
    if (!std::isfinite(t_s[i]) || !std::isfinite(value[i])) continue;
    if (std::binary_search(run.outliers.begin(), run.outliers.end(), i)) continue;  // a dropout or glitch
    out.tau.push_back(t_s[i] - run.t_cut_s);
    out.y.push_back(value[i]);
    moving += i < stop || !run.stopped;
  }
  const std::size_t n = out.tau.size();
  // ... and its weights (reading_noise.hpp, from the readings less the zero level as fit takes them),
  // so that the base model is fit's model of that name. The readings themselves keep their own zero:
  // a zero level fit subtracts is a sensor offset here, an effect to name.
  out.weight.assign(n, 1.0);
  if (opt.weighted) {
    std::vector<double> above_zero(out.y);
    for (double& v : above_zero) v -= out.zero_level;
    weigh_by_noise_into(above_zero, out.weight);
  }
  const double k = value_per_rad_per_s(q, opt.bench.kb_v_s_per_rad);
  // The reading's resolution and noise, the zero level's own uncertainty (a sensor offset is bounded
  // by it when the run shows a standstill), and the lowest reading the sensor gave at all.
  const double quantum = reading_quantum(out.y);
  out.reading_noise = std::max(
      reading_noise_sigma(std::span<const double>(out.y).first(std::max<std::size_t>(moving, std::min<std::size_t>(n, 3)))),
      1e-12);
  const std::size_t tail = n - std::min(moving, n);
  out.standstill_seen = run.stopped && tail >= 5;
  out.offset_lo = -std::numeric_limits<double>::infinity();
  out.offset_hi = std::numeric_limits<double>::infinity();
  if (out.standstill_seen) {
    // The reading at rest is measured: an offset lies between 0 and it, give or take its uncertainty.
    double sum = 0, sum2 = 0;
    for (std::size_t i = moving; i < n; ++i) sum += out.y[i], sum2 += out.y[i] * out.y[i];
    const double mean = sum / static_cast<double>(tail);
    const double spread = std::sqrt(std::max(sum2 / static_cast<double>(tail) - mean * mean, 0.0));
    double ymax = 0;
    for (double v : out.y) ymax = std::max(ymax, std::abs(v));
    const double slack = std::max({3.0 * std::max(spread, run.noise_level) / std::sqrt(static_cast<double>(tail)),
                                   0.5 * quantum, 1e-6 * ymax});
    out.offset_lo = std::min(0.0, out.zero_level) - slack;
    out.offset_hi = std::max(0.0, out.zero_level) + slack;
  }
  double lowest_reading = std::numeric_limits<double>::infinity();
  for (double v : value)
    if (std::isfinite(v)) lowest_reading = std::min(lowest_reading, v);
  EffectFitData data;
  data.tau = out.tau;
  data.y = out.y;
  data.weight = out.weight;
  data.moving = moving;
  data.k = k;
  data.inertia_kg_m2 = opt.bench.inertia_kg_m2;
  data.unit = out.unit;
  data.offset_lo = out.offset_lo;
  data.offset_hi = out.offset_hi;

  std::vector<const Effect*> model;
  for (const Effect& lib : effect_library())
    if (contains(opt.base, &lib)) model.push_back(&lib);
  out.base = fit_effects(model, data);
  out.final_fit = out.base;
  if (!std::isfinite(out.base.sse)) {
    out.message = fmt::format("the base model ({}) could not be fitted: {}", out.base.label(), out.base.message);
    return out;
  }
  out.ok = true;

  // Noise and bins: the period from the samples, bins of ~bin_s.
  const double span_s = n > 1 ? out.tau.back() - out.tau.front() : 0.0;
  const double period = n > 1 ? span_s / static_cast<double>(n - 1) : 0.02;
  // A short fast coast (a propeller's 1.5 s) gets bins of a tenth of it, so that its bend spans
  // several bins: three bins of half a second each would hold it all, and their jumps, the misfit
  // itself, would pass for noise.
  const double coast_s = moving > 1 ? out.tau[std::min(moving, n) - 1] - out.tau.front() : span_s;
  const double bin_s = std::min(opt.bin_s, std::max(coast_s, 0.0) / 10.0);
  const std::size_t m = std::max<std::size_t>(5, static_cast<std::size_t>(std::lround(bin_s / std::max(period, 1e-6))));
  out.bin_samples = m;
  const double noise = out.reading_noise;

  std::vector<const Effect*> pool = opt.candidates;
  if (pool.empty())
    for (const Effect& lib : effect_library()) pool.push_back(&lib);

  // A named effect must remove at least half of the systematic disagreement (chi-square excess
  // of the binned residual), not just shave the noise.
  constexpr double max_left = 0.5;
  // ... and move the model by at least half a reading step somewhere (else it fits rounding).
  EffectFit current = out.base;
  // Backward check after a step: an effect added at an earlier step may only have stood in for the
  // one just found (greedy order), and a term of the belief may not be needed at all once the
  // missing effect is in (viscous friction on a motor whose coast is Coulomb's alone). Each is
  // dropped, and said, when the model does as well without it; a friction term always stays.
  const auto drop_unneeded = [&](EffectFit& model, ExplainStep& st, double n_eff) {
    bool any = false;
    for (bool dropped = true; dropped;) {
      dropped = false;
      for (const Effect* e : model.effects) {
        if (e->name == st.added) continue;
        std::vector<const Effect*> reduced;
        for (const Effect* k2 : model.effects)
          if (k2 != e) reduced.push_back(k2);
        if (std::none_of(reduced.begin(), reduced.end(), [](const Effect* k2) { return k2->kind == EffectKind::torque; }))
          continue;
        EffectFit r = fit_effects(reduced, data, &model);
        if (!std::isfinite(r.sse) || r.sse <= 0) continue;
        const double cost = n_eff * std::log(r.sse / model.sse) - e->size() * std::log(n_eff);
        if (cost >= opt.min_delta_bic) continue;
        st.removed.emplace_back(e->name);
        const bool belief = contains(opt.base, e);
        st.why += fmt::format("; {} removed: not needed{} — the model without it fits as well (dBIC {:.1f} < {:.0f}){}",
                              e->name, belief ? " (a term of the starting model)" : "", cost, opt.min_delta_bic,
                              st.added.empty() ? std::string() : fmt::format(", {} covers it", st.added));
        model = std::move(r);
        st.fit = model;
        st.rmse_after = model.rmse;
        dropped = any = true;
        break;
      }
    }
    return any;
  };
  // The second of two effects that together fit better than any one effect alone (a lookahead:
  // windage and Coulomb friction on a fan, where Stribeck alone bends the coast almost as well and
  // the greedy choice would stop there): added at the next step whatever that step's residual says.
  const Effect* pending = nullptr;
  std::string pending_why;
  for (int step = 0;; ++step) {
    const std::vector<double> res = residual_of(out.y, current);
    const ResidualBins bins = bin_residuals(res, m, noise);
    if (step == 0) out.bin_noise = bins.bin_se;
    const std::vector<double> speed = model_speed(current, out.tau, k);
    std::vector<Disagreement> where = locate(bins, bins.bin_se, opt.systematic_z, out.tau, res, speed, run.t_cut_s);
    const double mass = systematic_mass(bins, bins.bin_se);
    if (where.empty() && mass_significant(mass, bins.mean.size()))
      // Spread out rather than concentrated: show where it is largest at a lower threshold.
      where = locate(bins, bins.bin_se, 0.6 * opt.systematic_z, out.tau, res, speed, run.t_cut_s);
    if (where.empty() && !mass_significant(mass, bins.mean.size()) && !pending) {
      out.remaining = where;
      out.conclusion = fmt::format(
          "nothing significant remains: no {:.2g}-s stretch of the residual is beyond {:.0f}x a bin's noise ({:.2g} {}), "
          "and the bins together are consistent with noise",
          double(m) * period, opt.systematic_z, bins.bin_se, out.unit);
      break;
    }
    if (step >= opt.max_steps) {
      out.remaining = where;
      out.conclusion = fmt::format("stopped after {} added effects; disagreement remains", step);
      break;
    }

    ExplainStep st;
    st.rmse_before = current.rmse;
    st.bin_noise = bins.bin_se;
    st.where = where;
    for (const Effect* c : pool) {
      if (contains(current.effects, c)) continue;
      CandidateTrial t;
      t.effect = std::string(c->name);
      t.fit = fit_effects(with_effect(current.effects, c), data, &current);
      st.trials.push_back(std::move(t));
    }
    if (st.trials.empty()) {
      out.remaining = where;
      out.conclusion = "disagreement remains, but every candidate effect is already in the model";
      break;
    }
    // Effective sample size from the best-fitting candidate's residual: correlated noise
    // (ripple, aliasing, quantization) inflates the variance of a bin mean beyond σ²/m.
    const CandidateTrial* lowest = nullptr;
    for (const auto& t : st.trials)
      if (std::isfinite(t.fit.sse) && (!lowest || t.fit.sse < lowest->fit.sse)) lowest = &t;
    double n_eff = static_cast<double>(n);
    if (lowest) {
      const ResidualBins lb = bin_residuals(residual_of(out.y, lowest->fit), m, noise);
      const double inflation = static_cast<double>(m) * lb.bin_se * lb.bin_se / (noise * noise);
      n_eff = std::clamp(static_cast<double>(n) / std::max(inflation, 1.0), 2.0, static_cast<double>(n));
    }
    // A sensor offset that would read below zero at standstill, on a sensor the recording shows
    // reading zero (at rest before the spin-up, or after the stop) and never below it, is not
    // physical, however well it fits: without a standstill in the window a viscous coast with Coulomb
    // friction is an exponential plus a constant, and so is one with a negative offset.
    const double tolerance = std::max(3 * noise, quantum);
    const bool reads_zero = lowest_reading <= tolerance && lowest_reading >= -tolerance;
    for (auto& t : st.trials) {
      const Parameter* off = t.fit.param("sensor_offset");
      if (!off || !std::isfinite(off->value)) continue;
      if (off->value < -tolerance && reads_zero)
        t.impossible = fmt::format("a sensor offset of {:.4g} {} would make the reading at standstill {:.4g} {}, below "
                                   "zero, and this sensor reads zero, never below it (its lowest reading in the "
                                   "recording: {:.4g} {})",
                                   off->value, out.unit, off->value, out.unit, lowest_reading, out.unit);
    }
    CandidateTrial* best = nullptr;
    for (auto& t : st.trials) {
      if (!std::isfinite(t.fit.sse) || t.fit.sse <= 0) {
        t.delta_bic = nan;
        t.verdict = fmt::format("could not be fitted ({})", t.fit.message);
        continue;
      }
      const int extra = static_cast<int>(t.fit.theta.size()) - static_cast<int>(current.theta.size());
      t.delta_bic = n_eff * std::log(current.sse / t.fit.sse) - extra * std::log(n_eff);
      const ResidualBins tb = bin_residuals(residual_of(out.y, t.fit), m, noise);
      t.systematic_after = mass > 0 ? systematic_mass(tb, bins.bin_se) / mass : 0.0;
      t.change = largest_change(current, t.fit, m);
      if (t.impossible.empty() && (!best || t.delta_bic > best->delta_bic)) best = &t;
    }
    // The pair added at the step before: its second effect now.
    const bool forced = pending != nullptr;
    if (forced) {
      for (auto& t : st.trials)
        if (t.effect == pending->name && t.impossible.empty() && std::isfinite(t.delta_bic) && t.delta_bic > 0) best = &t;
      if (!best || best->effect != pending->name) best = nullptr;
      pending = nullptr;
    }
    // Lookahead: two effects together against the best one alone. The pair must win by more than
    // the 3 in BIC within which two models cannot be told apart - by min_delta_bic, as a step
    // would, when it has more parameters than the best one alone, which must then leave a
    // systematic disagreement (else the greedy search rightly stops there: the residual is noise);
    // its second effect must add more than min_delta_bic to its first, and the pair move the model
    // by half a reading step somewhere. Between pairs within 3 of each other, fewer parameters.
    if (best && !forced && pool.size() >= 2) {
      struct Pair {
        const CandidateTrial *a, *b;
        double bic;
        std::size_t params;
      };
      std::vector<Pair> pairs;
      const ResidualBins left = bin_residuals(residual_of(out.y, best->fit), m, noise);
      const bool best_leaves_some = mass_significant(systematic_mass(left, bins.bin_se), left.mean.size());
      for (const auto& a : st.trials)
        for (const auto& b : st.trials) {
          if (&a >= &b || !a.impossible.empty() || !b.impossible.empty() || !std::isfinite(a.delta_bic) ||
              !std::isfinite(b.delta_bic))
            continue;
          const Effect* ea = find_effect(a.effect);
          const Effect* eb = find_effect(b.effect);
          if (!ea || !eb) continue;
          const bool more = a.fit.theta.size() + eb->size() > best->fit.theta.size();
          if (more && !best_leaves_some) continue;
          const EffectFit f = fit_effects(with_effect(with_effect(current.effects, ea), eb), data, &a.fit);
          if (!std::isfinite(f.sse) || f.sse <= 0) continue;
          const int extra = static_cast<int>(f.theta.size()) - static_cast<int>(current.theta.size());
          const double d = n_eff * std::log(current.sse / f.sse) - extra * std::log(n_eff);
          const double margin = more ? opt.min_delta_bic : 3.0;
          if (d > best->delta_bic + margin && d - std::max(a.delta_bic, b.delta_bic) > opt.min_delta_bic &&
              largest_change(current, f, m) >= 0.5 * quantum)
            pairs.push_back({&a, &b, d, f.theta.size()});
        }
      const Pair* chosen = nullptr;
      for (const Pair& p : pairs)
        if (!chosen || p.bic > chosen->bic) chosen = &p;
      for (const Pair& p : pairs)
        if (chosen && p.bic > chosen->bic - 3 && p.params < chosen->params) chosen = &p;
      const CandidateTrial* pa = chosen ? chosen->a : nullptr;
      const CandidateTrial* pb = chosen ? chosen->b : nullptr;
      const double pair_bic = chosen ? chosen->bic : 0.0;
      if (pa) {
        if (pb->delta_bic > pa->delta_bic) std::swap(pa, pb);
        pending = find_effect(pb->effect);
        pending_why = fmt::format("; with {} to follow: the two together fit better than {} alone (dBIC {:.1f} vs {:.1f})",
                                  pb->effect, best->effect, pair_bic, best->delta_bic);
        for (auto& t : st.trials)
          if (&t == pa) best = &t;
      }
    }
    // Evidence that cannot separate two effects (within 3 in BIC) goes to the simpler one.
    if (!pending && !forced)
      for (auto& t : st.trials)
        if (best && &t != best && t.impossible.empty() && std::isfinite(t.delta_bic) &&
            t.delta_bic > best->delta_bic - 3 && t.fit.theta.size() < best->fit.theta.size() &&
            t.systematic_after <= best->systematic_after + 0.05)
          best = &t;
    // As many parameters and within 3 in BIC: the run cannot tell them apart. The choice is fixed
    // (friction before a sensor effect, then library order) and said, never made silently.
    std::vector<CandidateTrial*> twins;
    if (best && !pending && !forced)
      for (auto& t : st.trials)
        if (&t != best && t.impossible.empty() && std::isfinite(t.delta_bic) &&
            std::abs(t.delta_bic - best->delta_bic) < 3 && t.fit.theta.size() == best->fit.theta.size() &&
            t.systematic_after < max_left && t.change >= 0.5 * quantum)
          twins.push_back(&t);
    if (!twins.empty()) {
      const auto rank = [](const CandidateTrial* t) {
        const Effect* e = find_effect(t->effect);
        return (e && e->kind == EffectKind::sensor ? 100 : 0) + (e ? static_cast<int>(e - effect_library().data()) : 99);
      };
      twins.push_back(best);
      std::sort(twins.begin(), twins.end(), [&](auto* a, auto* b) { return rank(a) < rank(b); });
      best = twins.front();
      twins.erase(twins.begin());
    }
    // A pair's first effect stands on the pair's evidence and change (checked when it was chosen),
    // its second on the step's own BIC.
    const bool enough = best && (pending || (best->delta_bic > opt.min_delta_bic &&
                                             (forced || (best->systematic_after < max_left && best->change >= 0.5 * quantum))));
    if (!enough) pending = nullptr;
    for (auto& t : st.trials) {
      if (!t.verdict.empty()) continue;
      if (&t == best && enough) {
        t.verdict = "added";
        continue;
      }
      if (!t.impossible.empty())
        t.verdict = fmt::format("not physical here: {} (dBIC {:.1f}, RMSE {:.4g} {})", t.impossible, t.delta_bic,
                                t.fit.rmse, out.unit);
      else if (enough && std::find(twins.begin(), twins.end(), &t) != twins.end())
        t.verdict = fmt::format("fits this run as well as {} (dBIC {:.1f} vs {:.1f}, RMSE {:.4g} vs {:.4g} {}): the run "
                                "cannot tell them apart",
                                best->effect, t.delta_bic, best->delta_bic, t.fit.rmse, best->fit.rmse, out.unit);
      else if (t.delta_bic <= opt.min_delta_bic)
        t.verdict = t.delta_bic <= 0 ? fmt::format("no real improvement (RMSE {:.4g} {}, dBIC {:.1f})", t.fit.rmse,
                                                   out.unit, t.delta_bic)
                                     : fmt::format("too little evidence (dBIC {:.1f} < {:.0f}, RMSE {:.4g} {})",
                                                   t.delta_bic, opt.min_delta_bic, t.fit.rmse, out.unit);
      else if (t.change < 0.5 * quantum)
        t.verdict = fmt::format("changes the model by {:.2g} {} at most, less than half the reading's resolution {:.2g} {} "
                                "(dBIC {:.1f})",
                                t.change, out.unit, quantum, out.unit, t.delta_bic);
      else if (t.systematic_after >= max_left)
        t.verdict = fmt::format("fits the noise, not the disagreement ({:.0f}% of it left, dBIC {:.1f})",
                                100 * t.systematic_after, t.delta_bic);
      else
        t.verdict = t.delta_bic > best->delta_bic
                        ? fmt::format("as good but not simpler (dBIC {:.1f} vs {:.1f} with fewer parameters, RMSE {:.4g} {})",
                                      t.delta_bic, best->delta_bic, t.fit.rmse, out.unit)
                        : fmt::format("explains less (dBIC {:.1f} vs {:.1f}, RMSE {:.4g} {}, {:.0f}% of the disagreement left)",
                                      t.delta_bic, best->delta_bic, t.fit.rmse, out.unit, 100 * t.systematic_after);
    }
    if (!enough) {
      out.remaining = where;
      out.conclusion = best ? fmt::format("no candidate explains what remains (best: {}, dBIC {:.1f}, {:.0f}% of the "
                                          "disagreement left); nothing added",
                                          best->effect, best->delta_bic, 100 * best->systematic_after)
                            : "no candidate could be fitted; nothing added";
      out.final_trials = std::move(st.trials);  // kept for the story: what was tried and why not
      break;
    }
    st.added = best->effect;
    st.rmse_after = best->fit.rmse;
    st.fit = best->fit;
    if (const Effect* e = find_effect(st.added)) {
      st.meaning = effect_meaning(*e, best->fit, best->fit.omega0);
      st.signature = effect_signature(*e, best->fit, best->fit.omega0);
    }
    if (!twins.empty()) {
      std::string names;
      double apart = 0;
      for (const CandidateTrial* t : twins) {
        st.indistinguishable.push_back(t->effect);
        names += (names.empty() ? "" : " or ") + t->effect;
        apart = std::max(apart, largest_change(best->fit, t->fit, m));
      }
      const bool offset_or_friction =
          std::any_of(twins.begin(), twins.end(), [](auto* t) { return t->effect == "sensor_offset"; }) ||
          best->effect == "sensor_offset";
      st.undecided = fmt::format(
          "{} or {}: this run cannot tell them apart (dBIC {:.1f} vs {:.1f}; their curves differ by at most {:.2g} {}, "
          "a bin's noise being {:.2g} {}){}; {} is kept by rule (friction before a sensor effect), not by the data",
          best->effect, names, best->delta_bic, twins.front()->delta_bic, apart, out.unit, bins.bin_se, out.unit,
          offset_or_friction && !out.standstill_seen
              ? ": without a standstill in the window the reading's zero is not measured, and friction that "
                "levels the coast off toward a speed below zero reads like a sensor offset; record the coast to "
                "its stop to decide"
              : "",
          best->effect);
    }
    st.why = fmt::format("{}: dBIC {:.1f} (n_eff {:.0f}), RMSE {:.4g} -> {:.4g} {} ({:.2g}x smaller), {:.0f}% of "
                         "the systematic disagreement left",
                         best->effect, best->delta_bic, n_eff, current.rmse, best->fit.rmse, out.unit,
                         current.rmse / best->fit.rmse, 100 * best->systematic_after);
    if (pending) st.why += pending_why;
    current = st.fit;
    drop_unneeded(current, st, n_eff);
    out.steps.push_back(std::move(st));
  }
  // The belief itself: a term of it the data do not need (viscous friction on a motor whose coast
  // is Coulomb's alone) is said and removed, as a step of its own when nothing was added.
  if (out.steps.empty() && current.effects.size() > 1) {
    ExplainStep st;
    st.rmse_before = current.rmse;
    st.fit = current;
    st.rmse_after = current.rmse;
    const ResidualBins bins = bin_residuals(residual_of(out.y, current), m, noise);
    st.bin_noise = bins.bin_se;
    const double inflation = static_cast<double>(m) * bins.bin_se * bins.bin_se / (noise * noise);
    const double n_eff = std::clamp(static_cast<double>(n) / std::max(inflation, 1.0), 2.0, static_cast<double>(n));
    if (drop_unneeded(current, st, n_eff)) {
      st.why = st.why.substr(std::min<std::size_t>(2, st.why.size()));  // no step added before it: no "; "
      out.conclusion += fmt::format("; then {} removed: not needed", fmt::join(st.removed, " and "));
      out.steps.push_back(std::move(st));
    }
  }
  out.final_fit = current;
  out.top_speed = current.omega0;
  for (std::size_t i = 0; i < out.steps.size(); ++i)
    if (!out.steps[i].undecided.empty()) {
      std::string names = out.steps[i].added;
      for (const auto& other : out.steps[i].indistinguishable) names += " or " + other;
      out.conclusion += fmt::format("; undecided at step {}: {} (this run cannot tell them apart)", i + 1, names);
    }
  return out;
}

ExplainResult explain_run(const Recording& rec, const Run& run, const ExplainOptions& opt) {
  return explain_run(rec.t_s, rec.value, rec.quantity, run, opt);
}

}  // namespace spindown
