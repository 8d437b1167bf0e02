#include "spindown/explain.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <limits>

#include "explain_residuals.hpp"
#include "spindown/fit_checks.hpp"
#include "spindown/reading_noise.hpp"

namespace spindown {

using namespace explain_detail;

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

namespace {

// A named effect must remove at least half of the systematic disagreement (chi-square excess
// of the binned residual), not just shave the noise.
constexpr double max_left = 0.5;

// The workflow on one run's window: the base model, then one effect a step while a systematic
// disagreement remains that a candidate explains (explain.hpp tells the rules).
class Explainer {
 public:
  Explainer(const RunWindow& window, Quantity q, const Run& run, const ExplainOptions& opt, double lowest_reading);
  ExplainResult run() &&;

 private:
  void take_window();
  void bound_the_offset();
  void choose_bins();
  bool fit_base();
  // One step: false when the workflow ends (out_.conclusion says why).
  bool step(int number);
  void try_candidates(ExplainStep& st) const;
  double effective_n(const ExplainStep& st) const;
  void rule_out_impossible(ExplainStep& st) const;
  std::string unresolved(const CandidateTrial& t, double n_eff) const;
  bool beyond_rounding(const EffectFit& f, double n_eff, std::string* said) const;
  CandidateTrial* score(ExplainStep& st, const ResidualBins& bins, double mass, double n_eff) const;
  CandidateTrial* look_ahead(ExplainStep& st, CandidateTrial* best, const ResidualBins& bins, double n_eff);
  std::vector<CandidateTrial*> twins_of(ExplainStep& st, CandidateTrial*& best) const;
  void write_verdicts(ExplainStep& st, const CandidateTrial* best, const std::vector<CandidateTrial*>& twins,
                      bool enough) const;
  void record(ExplainStep& st, const CandidateTrial& best, const std::vector<CandidateTrial*>& twins,
              const ResidualBins& bins, double n_eff);
  bool drop_unneeded(EffectFit& model, ExplainStep& st, double n_eff) const;
  void drop_unneeded_belief();
  void finish();

  const RunWindow& window_;
  const Run& run_;
  const ExplainOptions& opt_;
  ExplainResult out_;
  EffectFitData data_;
  double k_ = 1;
  double lowest_reading_ = 0;  // the lowest reading the sensor gave at all
  double quantum_ = 0;         // the reading's resolution
  std::size_t n_ = 0, moving_ = 0;
  std::vector<double> speed_;  // the measured speed at each sample (rad/s), where the story says it is
  std::size_t m_ = 5;          // samples per bin
  double period_ = 0.02;
  std::vector<const Effect*> pool_;
  EffectFit current_;
  // The second of two effects that together fit better than any one effect alone (a lookahead:
  // windage and Coulomb friction on a fan, where Stribeck alone bends the coast almost as well and
  // the greedy choice would stop there): added at the next step whatever that step's residual says.
  const Effect* pending_ = nullptr;
  std::string pending_why_;
};

Explainer::Explainer(const RunWindow& window, Quantity q, const Run& run, const ExplainOptions& opt,
                     double lowest_reading)
    : window_(window),
      run_(run),
      opt_(opt),
      k_(value_per_rad_per_s(q, opt.bench.kb_v_s_per_rad)),
      lowest_reading_(lowest_reading) {
  out_.run = run;
  out_.bench = opt.bench;
  out_.quantity = q;
  out_.unit = std::string(quantity_unit(q));
}

// spindown fit's samples and weights (run_window.hpp), so that the base model is fit's model of
// that name. The readings keep their own zero: a zero level fit subtracts is a sensor offset here,
// an effect to name.
void Explainer::take_window() {
  n_ = window_.size();
  moving_ = window_.moving();
  out_.zero_level = window_.zero_level();
  out_.tau.assign(window_.tau().begin(), window_.tau().end());
  out_.y.resize(n_);
  for (std::size_t i = 0; i < n_; ++i) out_.y[i] = window_.y()[i] + out_.zero_level;
  out_.weight.assign(window_.weight().begin(), window_.weight().end());
  out_.reading_noise = std::max(window_.reading_noise(), 1e-12);
  quantum_ = reading_quantum(out_.y);
  speed_ = measured_speed(out_.y, out_.zero_level, k_);
}

// The reading's zero is measured when the run shows a standstill: an offset lies between 0 and
// it, give or take its uncertainty; else it is free.
void Explainer::bound_the_offset() {
  const std::size_t tail = n_ - std::min(moving_, n_);
  out_.standstill_seen = run_.stopped && tail >= 5;
  out_.offset_lo = -std::numeric_limits<double>::infinity();
  out_.offset_hi = std::numeric_limits<double>::infinity();
  if (!out_.standstill_seen) return;
  double sum = 0, sum2 = 0;
  for (std::size_t i = moving_; i < n_; ++i) sum += out_.y[i], sum2 += out_.y[i] * out_.y[i];
  const double mean = sum / static_cast<double>(tail);
  const double spread = std::sqrt(std::max(sum2 / static_cast<double>(tail) - mean * mean, 0.0));
  double ymax = 0;
  for (double v : out_.y) ymax = std::max(ymax, std::abs(v));
  const double slack = std::max({3.0 * std::max(spread, run_.noise_level) / std::sqrt(static_cast<double>(tail)),
                                 0.5 * quantum_, 1e-6 * ymax});
  out_.offset_lo = std::min(0.0, out_.zero_level) - slack;
  out_.offset_hi = std::max(0.0, out_.zero_level) + slack;
}

// Bins of ~bin_s, the period from the samples. A short fast coast (a propeller's 1.5 s) gets bins
// of a tenth of it, so that its bend spans several bins: three bins of half a second each would
// hold it all, and their jumps, the misfit itself, would pass for noise.
void Explainer::choose_bins() {
  const double span_s = n_ > 1 ? out_.tau.back() - out_.tau.front() : 0.0;
  period_ = n_ > 1 ? span_s / static_cast<double>(n_ - 1) : 0.02;
  const double coast_s = moving_ > 1 ? out_.tau[std::min(moving_, n_) - 1] - out_.tau.front() : span_s;
  const double bin_s = std::min(opt_.bin_s, std::max(coast_s, 0.0) / 10.0);
  m_ = std::max<std::size_t>(5, static_cast<std::size_t>(std::lround(bin_s / std::max(period_, 1e-6))));
  out_.bin_samples = m_;
}

bool Explainer::fit_base() {
  data_.tau = out_.tau;
  data_.y = out_.y;
  data_.weight = out_.weight;
  data_.moving = moving_;
  data_.k = k_;
  data_.inertia_kg_m2 = opt_.bench.inertia_kg_m2;
  data_.unit = out_.unit;
  data_.offset_lo = out_.offset_lo;
  data_.offset_hi = out_.offset_hi;
  std::vector<const Effect*> model;
  for (const Effect& lib : effect_library())
    if (contains(opt_.base, &lib)) model.push_back(&lib);
  out_.base = fit_effects(model, data_);
  out_.final_fit = out_.base;
  if (!std::isfinite(out_.base.sse)) {
    out_.message = fmt::format("the base model ({}) could not be fitted: {}", out_.base.label(), out_.base.message);
    return false;
  }
  out_.ok = true;
  current_ = out_.base;
  pool_ = opt_.candidates;
  if (pool_.empty())
    for (const Effect& lib : effect_library()) pool_.push_back(&lib);
  return true;
}

ExplainResult Explainer::run() && {
  std::string why;
  if (!opt_.is_valid(&why)) {
    out_.message = why;
    return std::move(out_);
  }
  take_window();
  bound_the_offset();
  if (!fit_base()) return std::move(out_);
  choose_bins();
  for (int number = 0; step(number); ++number) {
  }
  drop_unneeded_belief();
  finish();
  return std::move(out_);
}

bool Explainer::step(int number) {
  const std::vector<double> res = residual_of(out_.y, current_);
  const ResidualBins bins = bin_residuals(res, m_, out_.reading_noise);
  if (number == 0) out_.bin_noise = bins.bin_se;
  std::vector<Disagreement> where =
      locate(bins, bins.bin_se, opt_.systematic_z, out_.tau, res, speed_, run_.t_cut_s);
  const double mass = systematic_mass(bins, bins.bin_se);
  if (where.empty() && mass_significant(mass, bins.mean.size()))
    // Spread out rather than concentrated: show where it is largest at a lower threshold.
    where = locate(bins, bins.bin_se, 0.6 * opt_.systematic_z, out_.tau, res, speed_, run_.t_cut_s);
  // No stretch stands out and the bins together look like noise: the candidates are still tried,
  // and one is added only on its own evidence (a short coast's bend spans a few bins, whose jumps
  // are the misfit itself and pass for the bins' noise).
  const bool quiet = where.empty() && !mass_significant(mass, bins.mean.size()) && !pending_;
  const auto nothing_remains = [&] {
    out_.remaining = where;
    out_.conclusion = fmt::format(
        "nothing significant remains: no {:.2g}-s stretch of the residual is beyond {:.0f}x a bin's noise ({:.2g} {}), "
        "and the bins together are consistent with noise",
        double(m_) * period_, opt_.systematic_z, bins.bin_se, out_.unit);
    return false;
  };
  if (number >= opt_.max_steps) {
    out_.remaining = where;
    out_.conclusion = fmt::format("stopped after {} added effects; disagreement remains", number);
    return false;
  }

  ExplainStep st;
  st.rmse_before = current_.rmse;
  st.bin_noise = bins.bin_se;
  st.where = where;
  try_candidates(st);
  if (quiet && st.trials.empty()) return nothing_remains();
  if (st.trials.empty()) {
    out_.remaining = where;
    out_.conclusion = "disagreement remains, but every candidate effect is already in the model";
    return false;
  }
  const double n_eff = effective_n(st);
  rule_out_impossible(st);
  CandidateTrial* best = score(st, bins, mass, n_eff);
  // The pair added at the step before: its second effect now.
  const bool forced = pending_ != nullptr;
  if (forced) {
    for (auto& t : st.trials)
      if (t.effect == pending_->name && t.impossible.empty() && std::isfinite(t.delta_bic) && t.delta_bic > 0) best = &t;
    if (!best || best->effect != pending_->name) best = nullptr;
    pending_ = nullptr;
  }
  if (best && !forced && pool_.size() >= 2) best = look_ahead(st, best, bins, n_eff);
  // Evidence that cannot separate two effects (within 3 in BIC) goes to the simpler one.
  if (!pending_ && !forced)
    for (auto& t : st.trials)
      if (best && &t != best && t.impossible.empty() && std::isfinite(t.delta_bic) &&
          t.delta_bic > best->delta_bic - 3 && t.fit.theta.size() < best->fit.theta.size() &&
          t.systematic_after <= best->systematic_after + 0.05)
        best = &t;
  const std::vector<CandidateTrial*> twins = best && !pending_ && !forced ? twins_of(st, best) : std::vector<CandidateTrial*>{};
  // A pair's first effect stands on the pair's evidence and change (checked when it was chosen),
  // its second on the step's own BIC.
  const bool enough =
      best && (pending_ || (best->delta_bic > opt_.min_delta_bic &&
                            (forced || (best->systematic_after < max_left && best->unresolved.empty()))));
  if (!enough) pending_ = nullptr;
  if (quiet && !enough) return nothing_remains();
  if (quiet)
    st.overall = fmt::format("no {:.2g}-s stretch stands out beyond {:.0f}x a bin's noise ({:.2g} {}), but a "
                             "candidate fits the whole run better on its own evidence",
                             double(m_) * period_, opt_.systematic_z, bins.bin_se, out_.unit);
  write_verdicts(st, best, twins, enough);
  if (!enough) {
    out_.remaining = where;
    out_.conclusion = best ? fmt::format("no candidate explains what remains (best: {}, dBIC {:.1f}, {:.0f}% of the "
                                         "disagreement left); nothing added",
                                         best->effect, best->delta_bic, 100 * best->systematic_after)
                           : "no candidate could be fitted; nothing added";
    out_.final_trials = std::move(st.trials);  // kept for the story: what was tried and why not
    return false;
  }
  record(st, *best, twins, bins, n_eff);
  return true;
}

void Explainer::try_candidates(ExplainStep& st) const {
  for (const Effect* c : pool_) {
    if (contains(current_.effects, c)) continue;
    CandidateTrial t;
    t.effect = std::string(c->name);
    t.fit = fit_effects(with_effect(current_.effects, c), data_, &current_);
    st.trials.push_back(std::move(t));
  }
}

// Effective sample size from the best-fitting candidate's residual: correlated noise (ripple,
// aliasing, quantization) inflates the variance of a bin mean beyond σ²/m.
double Explainer::effective_n(const ExplainStep& st) const {
  const CandidateTrial* lowest = nullptr;
  for (const auto& t : st.trials)
    if (std::isfinite(t.fit.sse) && (!lowest || t.fit.sse < lowest->fit.sse)) lowest = &t;
  const double n = static_cast<double>(n_);
  if (!lowest) return n;
  const double noise = out_.reading_noise;
  const ResidualBins lb = bin_residuals(residual_of(out_.y, lowest->fit), m_, noise);
  const double inflation = static_cast<double>(m_) * lb.bin_se * lb.bin_se / (noise * noise);
  return std::clamp(n / std::max(inflation, 1.0), 2.0, n);
}

// A sensor offset that would read below zero at standstill, on a sensor the recording shows
// reading zero (at rest before the spin-up, or after the stop) and never below it, is not
// physical, however well it fits: without a standstill in the window a viscous coast with Coulomb
// friction is an exponential plus a constant, and so is one with a negative offset.
void Explainer::rule_out_impossible(ExplainStep& st) const {
  const double tolerance = std::max(3 * out_.reading_noise, quantum_);
  const bool reads_zero = lowest_reading_ <= tolerance && lowest_reading_ >= -tolerance;
  for (auto& t : st.trials) {
    const Parameter* off = t.fit.param("sensor_offset");
    if (!off || !std::isfinite(off->value)) continue;
    if (off->value < -tolerance && reads_zero)
      t.impossible = fmt::format("a sensor offset of {:.4g} {} would make the reading at standstill {:.4g} {}, below "
                                 "zero, and this sensor reads zero, never below it (its lowest reading in the "
                                 "recording: {:.4g} {})",
                                 off->value, out_.unit, off->value, out_.unit, lowest_reading_, out_.unit);
  }
}

// Whether the readings resolve a change from the current model to f beyond rounding: a change of
// half a reading step somewhere, or, smaller, evidence (effective-sample BIC, as a step needs)
// from the bins where rounding is noise alone (evidence_beyond_rounding). *said: what was measured.
bool Explainer::beyond_rounding(const EffectFit& f, double n_eff, std::string* said) const {
  const double change = largest_change(current_, f, m_);
  if (change >= 0.5 * quantum_) return true;
  const RoundingFree ev = evidence_beyond_rounding(out_.y, out_.weight, current_, f, m_, quantum_, out_.reading_noise);
  const double scale = n_ > 0 ? n_eff / static_cast<double>(n_) : 1.0;
  const int extra = static_cast<int>(f.theta.size()) - static_cast<int>(current_.theta.size());
  const double evidence = ev.chi2_drop * scale - extra * std::log(std::max(scale * double(ev.samples), 2.0));
  if (ev.samples > 0 && evidence > opt_.min_delta_bic) return true;
  if (said)
    *said = ev.samples == 0
                ? fmt::format("changes the model by {:.2g} {} at most, less than half the reading's resolution {:.2g} {}, "
                              "and the readings dwell on each step (rounding's error is not noise there)",
                              change, out_.unit, quantum_, out_.unit)
                : fmt::format("changes the model by {:.2g} {} at most, less than half the reading's resolution {:.2g} {}, "
                              "and where the readings move a step a sample and rounding is noise ({} samples) the "
                              "evidence is {:.1f}",
                              change, out_.unit, quantum_, out_.unit, ev.samples, evidence);
  return false;
}

// Why the readings cannot tell a trial's change from their own artefacts, "" when they can:
// rounding (beyond_rounding), or dry friction beside viscous that only acts like an offset of the
// coast's tail within a converter's own (spindown fit's rule, check_fit: 2 reading steps or 0.2 %
// of the reading at the cut).
std::string Explainer::unresolved(const CandidateTrial& t, double n_eff) const {
  std::string said;
  if (!beyond_rounding(t.fit, n_eff, &said)) return said;
  const Parameter* dry = t.fit.param("c4");
  const Parameter* viscous = t.fit.param("c3");
  if (t.effect == "coulomb" && dry && viscous && viscous->value > 0) {
    const double offset = std::abs(k_ * dry->value / viscous->value);
    const double allowed = std::max(2.0 * quantum_, offset_allowance_fraction * std::abs(k_ * t.fit.omega0));
    if (offset <= allowed)
      return fmt::format("its dry friction acts like an offset of {:.2g} {} at the coast's end, within what a sensor "
                         "offset imitates (±{:.2g} {}: 2 reading steps or 0.2 % of the reading at the cut)",
                         offset, out_.unit, allowed, out_.unit);
  }
  return {};
}

// Each trial's evidence (BIC at the effective sample size), the disagreement it leaves and how
// far it moves the model; the best possible one by BIC.
CandidateTrial* Explainer::score(ExplainStep& st, const ResidualBins& bins, double mass, double n_eff) const {
  CandidateTrial* best = nullptr;
  for (auto& t : st.trials) {
    if (!std::isfinite(t.fit.sse) || t.fit.sse <= 0) {
      t.delta_bic = std::numeric_limits<double>::quiet_NaN();
      t.verdict = fmt::format("could not be fitted ({})", t.fit.message);
      continue;
    }
    const int extra = static_cast<int>(t.fit.theta.size()) - static_cast<int>(current_.theta.size());
    t.delta_bic = n_eff * std::log(current_.sse / t.fit.sse) - extra * std::log(n_eff);
    const ResidualBins tb = bin_residuals(residual_of(out_.y, t.fit), m_, out_.reading_noise);
    t.systematic_after = mass > 0 ? systematic_mass(tb, bins.bin_se) / mass : 0.0;
    t.change = largest_change(current_, t.fit, m_);
    t.unresolved = unresolved(t, n_eff);
    if (t.impossible.empty() && (!best || t.delta_bic > best->delta_bic)) best = &t;
  }
  return best;
}

// Lookahead: two effects together against the best one alone. The pair must win by more than
// the 3 in BIC within which two models cannot be told apart - by min_delta_bic, as a step
// would, when it has more parameters than the best one alone, which must then leave a
// systematic disagreement (else the greedy search rightly stops there: the residual is noise);
// its second effect must add more than min_delta_bic to its first, and the pair move the model
// by half a reading step somewhere. Between pairs within 3 of each other, fewer parameters.
// A pair chosen: its first effect is returned, its second is pending_.
CandidateTrial* Explainer::look_ahead(ExplainStep& st, CandidateTrial* best, const ResidualBins& bins, double n_eff) {
  struct Pair {
    const CandidateTrial *a, *b;
    double bic;
    std::size_t params;
  };
  std::vector<Pair> pairs;
  const ResidualBins left = bin_residuals(residual_of(out_.y, best->fit), m_, out_.reading_noise);
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
      const EffectFit f = fit_effects(with_effect(with_effect(current_.effects, ea), eb), data_, &a.fit);
      if (!std::isfinite(f.sse) || f.sse <= 0) continue;
      const int extra = static_cast<int>(f.theta.size()) - static_cast<int>(current_.theta.size());
      const double d = n_eff * std::log(current_.sse / f.sse) - extra * std::log(n_eff);
      const double margin = more ? opt_.min_delta_bic : 3.0;
      if (d > best->delta_bic + margin && d - std::max(a.delta_bic, b.delta_bic) > opt_.min_delta_bic &&
          beyond_rounding(f, n_eff, nullptr))
        pairs.push_back({&a, &b, d, f.theta.size()});
    }
  const Pair* chosen = nullptr;
  for (const Pair& p : pairs)
    if (!chosen || p.bic > chosen->bic) chosen = &p;
  for (const Pair& p : pairs)
    if (chosen && p.bic > chosen->bic - 3 && p.params < chosen->params) chosen = &p;
  if (!chosen) return best;
  const CandidateTrial* pa = chosen->a;
  const CandidateTrial* pb = chosen->b;
  if (pb->delta_bic > pa->delta_bic) std::swap(pa, pb);
  pending_ = find_effect(pb->effect);
  pending_why_ = fmt::format("; with {} to follow: the two together fit better than {} alone (dBIC {:.1f} vs {:.1f})",
                             pb->effect, best->effect, chosen->bic, best->delta_bic);
  for (auto& t : st.trials)
    if (&t == pa) best = &t;
  return best;
}

// As many parameters and within 3 in BIC: the run cannot tell them apart. The choice is fixed
// (friction before a sensor effect, then library order) and said, never made silently: best
// becomes the first by that rule, the others are returned.
std::vector<CandidateTrial*> Explainer::twins_of(ExplainStep& st, CandidateTrial*& best) const {
  std::vector<CandidateTrial*> twins;
  for (auto& t : st.trials)
    if (&t != best && t.impossible.empty() && std::isfinite(t.delta_bic) &&
        std::abs(t.delta_bic - best->delta_bic) < 3 && t.fit.theta.size() == best->fit.theta.size() &&
        t.systematic_after < max_left && t.unresolved.empty())
      twins.push_back(&t);
  if (twins.empty()) return twins;
  const auto rank = [](const CandidateTrial* t) {
    const Effect* e = find_effect(t->effect);
    return (e && e->kind == EffectKind::sensor ? 100 : 0) + (e ? static_cast<int>(e - effect_library().data()) : 99);
  };
  twins.push_back(best);
  std::sort(twins.begin(), twins.end(), [&](auto* a, auto* b) { return rank(a) < rank(b); });
  best = twins.front();
  twins.erase(twins.begin());
  return twins;
}

void Explainer::write_verdicts(ExplainStep& st, const CandidateTrial* best, const std::vector<CandidateTrial*>& twins,
                               bool enough) const {
  const std::string& unit = out_.unit;
  for (auto& t : st.trials) {
    if (!t.verdict.empty()) continue;
    if (&t == best && enough) {
      t.verdict = "added";
      continue;
    }
    if (!t.impossible.empty())
      t.verdict = fmt::format("not physical here: {} (dBIC {:.1f}, RMSE {:.4g} {})", t.impossible, t.delta_bic,
                              t.fit.rmse, unit);
    else if (enough && std::find(twins.begin(), twins.end(), &t) != twins.end())
      t.verdict = fmt::format("fits this run as well as {} (dBIC {:.1f} vs {:.1f}, RMSE {:.4g} vs {:.4g} {}): the run "
                              "cannot tell them apart",
                              best->effect, t.delta_bic, best->delta_bic, t.fit.rmse, best->fit.rmse, unit);
    else if (t.delta_bic <= opt_.min_delta_bic)
      t.verdict = t.delta_bic <= 0 ? fmt::format("no real improvement (RMSE {:.4g} {}, dBIC {:.1f})", t.fit.rmse,
                                                 unit, t.delta_bic)
                                   : fmt::format("too little evidence (dBIC {:.1f} < {:.0f}, RMSE {:.4g} {})",
                                                 t.delta_bic, opt_.min_delta_bic, t.fit.rmse, unit);
    else if (!t.unresolved.empty())
      t.verdict = fmt::format("{} (dBIC {:.1f})", t.unresolved, t.delta_bic);
    else if (t.systematic_after >= max_left)
      t.verdict = fmt::format("fits the noise, not the disagreement ({:.0f}% of it left, dBIC {:.1f})",
                              100 * t.systematic_after, t.delta_bic);
    else
      t.verdict = t.delta_bic > best->delta_bic
                      ? fmt::format("as good but not simpler (dBIC {:.1f} vs {:.1f} with fewer parameters, RMSE {:.4g} {})",
                                    t.delta_bic, best->delta_bic, t.fit.rmse, unit)
                      : fmt::format("explains less (dBIC {:.1f} vs {:.1f}, RMSE {:.4g} {}, {:.0f}% of the disagreement left)",
                                    t.delta_bic, best->delta_bic, t.fit.rmse, unit, 100 * t.systematic_after);
  }
}

// The step taken: its effect, what it means on this run, what the run cannot tell apart, why.
void Explainer::record(ExplainStep& st, const CandidateTrial& best, const std::vector<CandidateTrial*>& twins,
                       const ResidualBins& bins, double n_eff) {
  st.added = best.effect;
  st.rmse_after = best.fit.rmse;
  st.fit = best.fit;
  if (const Effect* e = find_effect(st.added)) {
    st.meaning = effect_meaning(*e, best.fit, best.fit.omega0);
    st.signature = effect_signature(*e, best.fit, best.fit.omega0);
  }
  if (!twins.empty()) {
    std::string names;
    double apart = 0;
    for (const CandidateTrial* t : twins) {
      st.indistinguishable.push_back(t->effect);
      names += (names.empty() ? "" : " or ") + t->effect;
      apart = std::max(apart, largest_change(best.fit, t->fit, m_));
    }
    const bool offset_or_friction =
        std::any_of(twins.begin(), twins.end(), [](auto* t) { return t->effect == "sensor_offset"; }) ||
        best.effect == "sensor_offset";
    st.undecided = fmt::format(
        "{} or {}: this run cannot tell them apart (dBIC {:.1f} vs {:.1f}; their curves differ by at most {:.2g} {}, "
        "a bin's noise being {:.2g} {}){}; {} is kept by rule (friction before a sensor effect), not by the data",
        best.effect, names, best.delta_bic, twins.front()->delta_bic, apart, out_.unit, bins.bin_se, out_.unit,
        offset_or_friction && !out_.standstill_seen
            ? ": without a standstill in the window the reading's zero is not measured, and friction that "
              "levels the coast off toward a speed below zero reads like a sensor offset; record the coast to "
              "its stop to decide"
            : "",
        best.effect);
  }
  st.why = fmt::format("{}: dBIC {:.1f} (n_eff {:.0f}), RMSE {:.4g} -> {:.4g} {} ({:.2g}x smaller), {:.0f}% of "
                       "the systematic disagreement left",
                       best.effect, best.delta_bic, n_eff, current_.rmse, best.fit.rmse, out_.unit,
                       current_.rmse / best.fit.rmse, 100 * best.systematic_after);
  if (pending_) st.why += pending_why_;
  current_ = st.fit;
  drop_unneeded(current_, st, n_eff);
  out_.steps.push_back(std::move(st));
}

// Backward check after a step: an effect added at an earlier step may only have stood in for the
// one just found (greedy order), and a term of the belief may not be needed at all once the
// missing effect is in (viscous friction on a motor whose coast is Coulomb's alone). Each is
// dropped, and said, when the model does as well without it; a friction term always stays.
bool Explainer::drop_unneeded(EffectFit& model, ExplainStep& st, double n_eff) const {
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
      EffectFit r = fit_effects(reduced, data_, &model);
      if (!std::isfinite(r.sse) || r.sse <= 0) continue;
      const double cost = n_eff * std::log(r.sse / model.sse) - e->size() * std::log(n_eff);
      if (cost >= opt_.min_delta_bic) continue;
      st.removed.emplace_back(e->name);
      const bool belief = contains(opt_.base, e);
      st.why += fmt::format("; {} removed: not needed{} — the model without it fits as well (dBIC {:.1f} < {:.0f}){}",
                            e->name, belief ? " (a term of the starting model)" : "", cost, opt_.min_delta_bic,
                            st.added.empty() ? std::string() : fmt::format(", {} covers it", st.added));
      model = std::move(r);
      st.fit = model;
      st.rmse_after = model.rmse;
      dropped = any = true;
      break;
    }
  }
  return any;
}

// The belief itself: a term of it the data do not need (viscous friction on a motor whose coast
// is Coulomb's alone) is said and removed, as a step of its own when nothing was added.
void Explainer::drop_unneeded_belief() {
  if (!out_.steps.empty() || current_.effects.size() <= 1) return;
  ExplainStep st;
  st.rmse_before = current_.rmse;
  st.fit = current_;
  st.rmse_after = current_.rmse;
  const double noise = out_.reading_noise;
  const ResidualBins bins = bin_residuals(residual_of(out_.y, current_), m_, noise);
  st.bin_noise = bins.bin_se;
  const double inflation = static_cast<double>(m_) * bins.bin_se * bins.bin_se / (noise * noise);
  const double n = static_cast<double>(n_);
  const double n_eff = std::clamp(n / std::max(inflation, 1.0), 2.0, n);
  if (drop_unneeded(current_, st, n_eff)) {
    st.why = st.why.substr(std::min<std::size_t>(2, st.why.size()));  // no step added before it: no "; "
    out_.conclusion += fmt::format("; then {} removed: not needed", fmt::join(st.removed, " and "));
    out_.steps.push_back(std::move(st));
  }
}

void Explainer::finish() {
  out_.final_fit = current_;
  out_.top_speed = current_.omega0;
  for (std::size_t i = 0; i < out_.steps.size(); ++i)
    if (!out_.steps[i].undecided.empty()) {
      std::string names = out_.steps[i].added;
      for (const auto& other : out_.steps[i].indistinguishable) names += " or " + other;
      out_.conclusion += fmt::format("; undecided at step {}: {} (this run cannot tell them apart)", i + 1, names);
    }
}

}  // namespace

ExplainResult explain_run(const RunWindow& window, Quantity q, const Run& run, const ExplainOptions& opt,
                          double lowest_reading) {
  return Explainer(window, q, run, opt, lowest_reading).run();
}

ExplainResult explain_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
                          const ExplainOptions& opt) {
  return explain_run(RunWindow(t_s, value, run, opt.weighted), q, run, opt, lowest_reading(value));
}

ExplainResult explain_run(const Recording& rec, const Run& run, const ExplainOptions& opt) {
  return explain_run(rec.t_s, rec.value, rec.quantity, run, opt);
}

double lowest_reading(std::span<const double> value) {
  double lowest = std::numeric_limits<double>::infinity();
  for (double v : value)
    if (std::isfinite(v)) lowest = std::min(lowest, v);
  return lowest;
}

}  // namespace spindown
