#include "spindown/motor_health.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <fmt/format.h>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "spindown/bench.hpp"

namespace spindown {

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr double rad_s_per_rpm = 2.0 * std::numbers::pi / 60.0;

struct Estimate {
  double value = 0;
  double se = 0;
};

std::optional<Estimate> param_of(const ModelFit* m, std::string_view name) {
  if (!m) return std::nullopt;
  const Parameter* p = m->param(name);
  if (!p || !std::isfinite(p->value)) return std::nullopt;
  return Estimate{p->value, std::isfinite(p->std_error) ? std::fabs(p->std_error) : 0.0};
}

double omega0_of(const ModelFit& m) {
  if (auto w = param_of(&m, "omega0")) return w->value;
  return m.omega0;
}

// Friction of one fitted model as viscous + Coulomb terms (a pure model has the other term 0).
struct FittedFriction {
  Estimate viscous, coulomb;
  double omega0 = 0;
  std::string model;
};

std::optional<FittedFriction> friction_of(const ModelFit* m) {
  if (!m || !m->converged) return std::nullopt;
  FittedFriction f;
  f.omega0 = omega0_of(*m);
  f.model = std::string(model_name(m->kind));
  switch (m->kind) {
    case ModelKind::viscous:
      if (auto c = param_of(m, "c1")) f.viscous = *c; else return std::nullopt;
      break;
    case ModelKind::coulomb:
      if (auto c = param_of(m, "c2")) f.coulomb = *c; else return std::nullopt;
      break;
    case ModelKind::combined: {
      auto cv = param_of(m, "c3");
      auto cc = param_of(m, "c4");
      if (!cv || !cc) return std::nullopt;
      f.viscous = *cv;
      f.coulomb = *cc;
      break;
    }
  }
  return f;
}

// Seconds for J·dω/dt = −(c_v·ω + c_c) to go from w_from down to w_to (inf if it never gets there).
double coast_time(double c_v, double c_c, double J, double w_from, double w_to) {
  if (!(w_from > w_to)) return 0;
  if (c_v > 0) {
    const double knee = c_c / c_v;  // speed scale where both terms are equal
    if (w_to + knee <= 0) return inf;
    return J / c_v * std::log((w_from + knee) / (w_to + knee));
  }
  if (c_c > 0) return J * (w_from - w_to) / c_c;
  return inf;
}

double ratio_se(double a, double sa, double b, double sb) {
  if (a == 0 || b == 0) return inf;
  const double r = a / b;
  return std::fabs(r) * std::hypot(sa / a, sb / b);
}

// Flagged when the ratio is past a threshold and significant: it differs from 1 (the motor as
// the reference describes it) by more than significance_sigma standard errors, so a ratio that
// is past the threshold only by noise is not flagged.
HealthLevel level_for_ratio(double r, double sr, const HealthThresholds& th) {
  const bool significant = std::fabs(r - 1.0) > th.significance_sigma * sr;
  if (!significant) return HealthLevel::ok;
  if (r >= th.service_ratio) return HealthLevel::service;
  if (r >= th.check_ratio) return HealthLevel::check;
  if (r <= 1.0 / th.check_ratio) return HealthLevel::check;  // far lower than expected: suspicious too
  return HealthLevel::ok;
}

std::string times(double r) {
  if (r < 0.095) return fmt::format("{:.2f}×", r);
  return r < 9.95 ? fmt::format("{:.1f}×", r) : fmt::format("{:.0f}×", r);
}

std::string seconds(double t) { return std::isfinite(t) ? fmt::format("{:.1f} s", t) : std::string("never"); }

// "stops 40 % sooner than the datasheet predicts (16.2 s vs 27.0 s)"
std::string stop_comparison(double t, double t_ref, std::string_view who) {
  if (!std::isfinite(t) || !std::isfinite(t_ref) || t_ref <= 0)
    return fmt::format("stops in {}, {} predicts {}", seconds(t), who, seconds(t_ref));
  const double change = (t / t_ref - 1.0) * 100.0;
  if (std::fabs(change) < 0.5)
    return fmt::format("stops when {} predicts ({} vs {})", who, seconds(t), seconds(t_ref));
  return fmt::format("stops {:.0f} % {} than {} predicts ({} vs {})", std::fabs(change),
                     change < 0 ? "sooner" : "later", who, seconds(t), seconds(t_ref));
}

// A ratio finding with the words for its level.
HealthFinding ratio_finding(std::string what, Estimate value, Estimate reference, std::string reference_name,
                            std::string unit, const HealthThresholds& th, std::string_view high_advice,
                            std::string_view low_advice, std::string_view against) {
  HealthFinding f;
  f.what = std::move(what);
  f.value = value.value;
  f.std_error = value.se;
  f.reference = reference.value;
  f.reference_std_error = reference.se;
  f.reference_name = std::move(reference_name);
  f.unit = std::move(unit);
  f.ratio = value.value / reference.value;
  f.ratio_std_error = ratio_se(value.value, value.se, reference.value, reference.se);
  f.level = level_for_ratio(f.ratio, f.ratio_std_error, th);
  const std::string head = fmt::format("{} {} {}", f.what, times(f.ratio), against);
  const std::string pm = fmt::format("±{:.2g}", f.ratio_std_error);
  if (f.level != HealthLevel::ok)
    f.reason = fmt::format("{} ({}): {}", head, pm, f.ratio > 1 ? high_advice : low_advice);
  else if (f.ratio >= th.check_ratio || f.ratio <= 1.0 / th.check_ratio)
    f.reason = fmt::format("{}, but within its uncertainty ({}): not flagged", head, pm);
  else
    f.reason = fmt::format("{} ({}): as expected", head, pm);
  return f;
}

HealthFinding note_finding(std::string what, HealthLevel level, std::string reason) {
  HealthFinding f;
  f.what = std::move(what);
  f.level = level;
  f.reason = std::move(reason);
  f.value = nan;
  f.reference = nan;
  return f;
}

// What the two ratios say together (issue 43): viscous friction up while dry friction reads
// *down* is electrical braking, not grease. A resistance across the motor's terminals (its leads
// left on a switched-off driver, a meter on them) draws current and brakes in proportion to
// speed, and divides the terminal voltage that is read, so dry friction reads lower; grease and
// wear never lower dry friction. So the first advice is the leads. (Viscous up with dry friction
// as it was stays "lubrication": too thick a grease does that too.)
//
// Dry friction changed while viscous friction did not, and the speed at the cut reads changed by
// the same factor: the reading's scale (K_b, a divider, the converter's reference: a 3.3 V board
// running a sketch written for 5 V). A reading k times the back-EMF leaves the exponential's rate
// (c3) alone, scales the linear fall (c4) by k, and reads the speed at the cut k times what the
// same supply gives; worn bearings change none but the friction.
void name_the_cause(HealthFinding& dry, HealthFinding& viscous, double omega0, const HealthBaseline& b) {
  const double w_ratio = b.omega0 > 0 && omega0 > 0 ? omega0 / b.omega0 : 0;
  const double w_tol = b.omega0 > 0 ? std::max(0.05, 2.0 * b.omega0_spread / b.omega0) : 0;
  if (dry.level != HealthLevel::ok && std::fabs(viscous.ratio - 1.0) <= std::max(2.0 * viscous.ratio_std_error, 0.1) &&
      w_ratio > 0 && std::fabs(w_ratio - 1.0) > w_tol && std::fabs(w_ratio / dry.ratio - 1.0) <= std::max(w_tol, 0.1)) {
    dry.reason = fmt::format(
        "dry friction {} the baseline (±{:.2g}) with viscous friction as it was ({}) and the speed at the cut read {} "
        "the baseline runs' ({:.0f} rad/s against {:.0f}): the reading's scale, not friction — the same supply gives "
        "the same speed, and a reading k times the back-EMF scales the linear fall (c4) and the speed by k and leaves "
        "the exponential's rate (c3) alone; check K_b, a divider on the input and the converter's reference (a 3.3 V "
        "board running a sketch written for 5 V)",
        times(dry.ratio), dry.ratio_std_error, times(viscous.ratio), times(w_ratio), omega0, b.omega0);
    return;
  }
  const bool dry_down = dry.ratio < 1.0 - std::max(2.0 * dry.ratio_std_error, 0.05);
  if (viscous.level == HealthLevel::ok || viscous.ratio <= 1 || !dry_down) return;
  viscous.reason = fmt::format(
      "viscous friction {} the baseline (±{:.2g}) while dry friction reads lower ({}): electrical braking, not "
      "grease — a resistance across the motor's terminals (its leads left on a switched-off driver, a meter on "
      "them) brakes in proportion to speed and divides the voltage read; check that the motor's leads are "
      "disconnected, then lubrication",
      times(viscous.ratio), viscous.ratio_std_error, times(dry.ratio));
  if (dry.level != HealthLevel::ok)
    dry.reason = fmt::format("dry friction {} the baseline: the voltage read divided by that load, not less friction",
                             times(dry.ratio));
}

// Dry and viscous friction both the same round multiple of the baseline (×20, ×50, ×60, ×1000,
// or a tenth…): time read in the wrong unit scales both rates alike (a sample number taken for
// milliseconds of a 20-ms loop gives ×20, seconds for minutes ×60, µs for ms ×1000), and a scale
// of the reading alike; wear does not land on a round number for both. Not judged, and said.
std::optional<std::string> round_multiple(const std::vector<HealthFinding>& findings) {
  const HealthFinding* dry = nullptr;
  const HealthFinding* viscous = nullptr;
  for (const auto& f : findings) {
    if (f.what == "dry friction" && f.ratio > 0) dry = &f;
    if (f.what == "viscous friction" && f.ratio > 0) viscous = &f;
  }
  if (!dry || !viscous || std::fabs(dry->ratio / viscous->ratio - 1.0) > 0.05) return std::nullopt;
  const double r = std::sqrt(dry->ratio * viscous->ratio);
  for (const double k : {10.0, 20.0, 50.0, 60.0, 100.0, 1000.0}) {
    for (const double m : {k, 1.0 / k}) {
      if (std::fabs(r / m - 1.0) > 0.05) continue;
      return fmt::format("not judged: dry and viscous friction are both {} the baseline ({} and {}): one round "
                         "factor on both is the signature of a time unit or a scale, not of wear (a sample number "
                         "read as milliseconds of a {:g}-ms loop, seconds as minutes, µs as ms) — check the time "
                         "column and its unit (--time-unit, --period-ms) before the motor",
                         times(m), times(dry->ratio), times(viscous->ratio), m >= 1 ? m : 1.0 / m);
    }
  }
  return std::nullopt;
}

void compare_with_baseline(const FittedFriction& fr, double J, const HealthBaseline& b, const HealthThresholds& th,
                           std::vector<HealthFinding>& out) {
  // A single run scatters around the baseline by the run-to-run spread as well as by the
  // baseline's own standard error: both widen the reference.
  const Estimate ref_c{b.c_coulomb, std::hypot(b.c_coulomb_stderr, b.c_coulomb_spread)};
  const Estimate ref_v{b.c_viscous, std::hypot(b.c_viscous_stderr, b.c_viscous_spread)};
  if (ref_c.value > 0)
    out.push_back(ratio_finding("dry friction", fr.coulomb, ref_c, "baseline", "N*m", th,
                                "check bearings and alignment",
                                "far below the known-good motor: check the bench's inertia J and that the "
                                "flywheel is fixed to the shaft",
                                "the baseline"));
  else
    out.push_back(note_finding("dry friction", HealthLevel::ok, "baseline dry friction is not positive: not compared"));
  if (ref_v.value > 0)
    out.push_back(ratio_finding("viscous friction", fr.viscous, ref_v, "baseline", "N*m*s/rad", th,
                                "check lubrication (old, dirty or too thick grease) and brush drag",
                                "far below the known-good motor: check the bench's inertia J",
                                "the baseline"));
  else
    out.push_back(
        note_finding("viscous friction", HealthLevel::ok, "baseline viscous friction is not positive: not compared"));

  if (ref_c.value > 0 && ref_v.value > 0) name_the_cause(out[out.size() - 2], out.back(), fr.omega0, b);

  // What the known-good motor would have done from this run's speed at the cut.
  const double t_run = coast_time(fr.viscous.value, fr.coulomb.value, J, fr.omega0, 0);
  const double t_base = coast_time(b.c_viscous, b.c_coulomb, J, fr.omega0, 0);
  HealthFinding stop = note_finding("stop time vs baseline", HealthLevel::ok,
                                    stop_comparison(t_run, t_base, "the baseline"));
  stop.value = t_run;
  stop.reference = t_base;
  stop.reference_name = "baseline";
  stop.unit = "s";
  if (std::isfinite(t_run) && std::isfinite(t_base) && t_base > 0) {
    stop.ratio = t_run / t_base;
    if (std::fabs(stop.ratio - 1.0) > th.stop_change_fraction) {
      stop.level = HealthLevel::check;
      stop.reason = stop.ratio < 1 ? stop.reason + ": friction has grown since the baseline — check bearings and "
                                                   "lubrication"
                                   : stop.reason + ": friction has fallen since the baseline — check the bench's "
                                                   "inertia J and that the flywheel is fixed";
    }
  }
  out.push_back(std::move(stop));
}

void compare_with_datasheet(const FittedFriction& fr, double J, const MotorDatasheet& ds,
                            const HealthThresholds& th, std::vector<HealthFinding>& out) {
  const auto t_ref = ds.no_load_friction_torque();
  if (!t_ref) return;
  const bool at_no_load = ds.no_load_speed_rpm.has_value();
  const double w = at_no_load ? *ds.no_load_speed_rpm * rad_s_per_rpm : fr.omega0;
  // Standard errors combined as if independent: c_v and c_c are usually anti-correlated, so this
  // errs on the wide (cautious) side.
  const Estimate torque{fr.viscous.value * w + fr.coulomb.value, std::hypot(w * fr.viscous.se, fr.coulomb.se)};
  const std::string what = at_no_load ? "friction at no-load speed" : "friction at the cut's speed";
  HealthFinding f = ratio_finding(what, torque, {*t_ref, 0}, "datasheet", "N*m", th,
                                  "check bearings, brushes and alignment",
                                  "far below what the datasheet allows: check the bench's inertia J and K_b",
                                  fmt::format("the datasheet's k_M·I0 = {:.3g} mN·m{}", *t_ref * 1e3,
                                              at_no_load ? fmt::format(" at {:.0f} rpm", *ds.no_load_speed_rpm)
                                                         : std::string(" (no no-load speed given)")));
  // The datasheet's prediction: this run's friction shape scaled to k_M·I0 at that speed, so the
  // predicted stop scales by the torque ratio.
  const double t_run = coast_time(fr.viscous.value, fr.coulomb.value, J, fr.omega0, 0);
  const double t_ds = t_run * f.ratio;
  const std::string stop_words = stop_comparison(t_run, t_ds, "the datasheet");
  if (f.level != HealthLevel::ok && std::isfinite(t_ds)) f.reason = stop_words + "; " + f.reason;
  out.push_back(std::move(f));
  HealthFinding stop = note_finding("stop time vs datasheet", HealthLevel::ok, stop_words);
  stop.value = t_run;
  stop.reference = t_ds;
  stop.reference_name = "datasheet";
  stop.unit = "s";
  if (std::isfinite(t_run) && std::isfinite(t_ds) && t_ds > 0) {
    stop.ratio = t_run / t_ds;
    stop.std_error = t_run * (torque.value != 0 ? torque.se / std::fabs(torque.value) : 0);
  }
  out.push_back(std::move(stop));
}

void lab_rules(const RunFit& fit, const ModelFit* best, const HealthThresholds& th, std::vector<HealthFinding>& out) {
  const double J = fit.bench.inertia_kg_m2;
  // Too long to slow down.
  if (auto fr = friction_of(best)) {
    const double t_slow =
        coast_time(fr->viscous.value, fr->coulomb.value, J, fr->omega0, fr->omega0 * (1.0 - th.slowdown_fraction));
    HealthFinding f;
    f.what = "time to slow down";
    f.value = t_slow;
    f.reference = th.max_slowdown_s;
    f.reference_name = "lab limit";
    f.unit = "s";
    const std::string head = fmt::format("loses {:.0f} % of its speed in {} ({} model; lab limit {})",
                                         th.slowdown_fraction * 100, seconds(t_slow), fr->model,
                                         seconds(th.max_slowdown_s));
    if (!(t_slow <= th.max_slowdown_s)) {
      f.level = HealthLevel::check;
      f.reason = fmt::format("too long to slow down: {}: friction unusually low or the motor still driven — "
                             "check that the supply was really cut and the bench's J",
                             head);
    } else {
      f.reason = head;
    }
    out.push_back(std::move(f));
  }
  // Too long to stop: the measured stop when there is one, else the best model's prediction.
  double t_stop = nan;
  std::string how;
  if (fit.run.stopped && std::isfinite(fit.run.t_stop_s)) {
    t_stop = fit.run.t_stop_s - fit.run.t_cut_s;
    how = "measured";
  } else if (best && best->converged) {
    t_stop = best->t_stop_pred_s;
    how = fmt::format("{} model's prediction", model_name(best->kind));
  }
  if (how.empty()) return;
  HealthFinding f;
  f.what = "time to stop";
  f.value = t_stop;
  f.reference = th.max_stop_s;
  f.reference_name = "lab limit";
  f.unit = "s";
  const std::string head = std::isfinite(t_stop)
                               ? fmt::format("stops {} after the cut ({}; lab limit {})", seconds(t_stop), how,
                                             seconds(th.max_stop_s))
                               : fmt::format("never stops ({}; lab limit {})", how, seconds(th.max_stop_s));
  if (!(t_stop <= th.max_stop_s)) {
    f.level = HealthLevel::check;
    f.reason = fmt::format("too long to stop: {}: check that the reading returns to zero (sensor offset) and "
                           "that the supply was cut",
                           head);
  } else {
    f.reason = head;
  }
  out.push_back(std::move(f));
}

const ModelFit* best_of(const RunFit& fit) {
  for (const auto& m : fit.models)
    if (model_name(m.kind) == fit.best && m.converged) return &m;
  return nullptr;
}

}  // namespace

std::string_view health_level_name(HealthLevel level) {
  switch (level) {
    case HealthLevel::not_judged: return "not_judged";
    case HealthLevel::ok: return "ok";
    case HealthLevel::check: return "check";
    case HealthLevel::service: return "service";
  }
  return "ok";
}

std::optional<HealthLevel> parse_health_level(std::string_view name) {
  for (HealthLevel l : {HealthLevel::not_judged, HealthLevel::ok, HealthLevel::check, HealthLevel::service})
    if (health_level_name(l) == name) return l;
  return std::nullopt;
}

std::optional<double> MotorDatasheet::torque_constant() const {
  if (torque_constant_nm_per_a) return torque_constant_nm_per_a;
  if (speed_constant_rpm_per_v && *speed_constant_rpm_per_v > 0) return kb_from_speed_constant(*speed_constant_rpm_per_v);
  return std::nullopt;
}

std::optional<double> MotorDatasheet::no_load_friction_torque() const {
  const auto k = torque_constant();
  if (!k || !no_load_current_a) return std::nullopt;
  return *k * *no_load_current_a;
}

bool MotorDatasheet::empty() const {
  return !speed_constant_rpm_per_v && !no_load_speed_rpm && !no_load_current_a && !torque_constant_nm_per_a &&
         !rotor_inertia_kg_m2;
}

bool HealthThresholds::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (!(check_ratio > 1 && std::isfinite(check_ratio))) return fail(fmt::format("check_ratio {} must be above 1", check_ratio));
  if (!(service_ratio >= check_ratio && std::isfinite(service_ratio)))
    return fail(fmt::format("service_ratio {} must be at least check_ratio {}", service_ratio, check_ratio));
  if (!(significance_sigma >= 0 && significance_sigma <= 10))
    return fail(fmt::format("significance_sigma {} not in [0, 10]", significance_sigma));
  if (!(max_slowdown_s > 0)) return fail(fmt::format("max_slowdown_s {} must be positive", max_slowdown_s));
  if (!(slowdown_fraction > 0 && slowdown_fraction < 1))
    return fail(fmt::format("slowdown_fraction {} not in (0, 1)", slowdown_fraction));
  if (!(max_stop_s > 0)) return fail(fmt::format("max_stop_s {} must be positive", max_stop_s));
  if (!(stop_change_fraction > 0 && stop_change_fraction < 1))
    return fail(fmt::format("stop_change_fraction {} not in (0, 1)", stop_change_fraction));
  return true;
}

std::optional<FrictionEstimate> combined_friction(const RunFit& fit) {
  const auto f = friction_of(fit.model(ModelKind::combined));
  if (!f) return std::nullopt;
  return FrictionEstimate{f->viscous.value, f->viscous.se, f->coulomb.value, f->coulomb.se};
}

HealthVerdict assess_health(const RunFit& fit, const MotorHealthConfig& cfg) {
  HealthVerdict v;
  const HealthThresholds& th = cfg.thresholds;
  const double J = fit.bench.inertia_kg_m2;
  const bool datasheet_torque = cfg.datasheet && cfg.datasheet->no_load_friction_torque().has_value();
  v.has_reference = datasheet_torque || cfg.baseline.has_value();

  // A doubted run (readings in other units than taken, a model that misses) is not the motor's
  // friction as it stands: no verdict is drawn from it, whatever the numbers say.
  if (!fit.doubts.empty()) {
    v.level = HealthLevel::not_judged;
    v.reason = fmt::format("the run is doubted ({}) — resolve that first; its friction is not compared",
                           fit.doubts.front());
    return v;
  }

  const ModelFit* best = best_of(fit);
  const ModelFit* combined = fit.model(ModelKind::combined);
  const auto combined_fr = friction_of(combined);

  if (!best) {
    v.findings.push_back(note_finding("fit", HealthLevel::check,
                                      "no model converged: the run cannot be judged — repeat the run"));
  }
  if (cfg.baseline) {
    if (combined_fr)
      compare_with_baseline(*combined_fr, J, *cfg.baseline, th, v.findings);
    else if (best)
      v.findings.push_back(note_finding("baseline", HealthLevel::check,
                                        "the combined model did not converge, so the friction cannot be compared "
                                        "with the baseline — repeat the run"));
  }
  if (const auto why = round_multiple(v.findings)) {
    v.level = HealthLevel::not_judged;
    v.reason = *why;
    return v;
  }
  if (datasheet_torque) {
    // The datasheet gives one torque, so the best model alone can be compared when the combined one failed.
    if (auto fr = combined_fr ? combined_fr : friction_of(best))
      compare_with_datasheet(*fr, J, *cfg.datasheet, th, v.findings);
  }
  if (cfg.datasheet && cfg.datasheet->rotor_inertia_kg_m2 && J < *cfg.datasheet->rotor_inertia_kg_m2) {
    HealthFinding f = note_finding(
        "inertia", HealthLevel::check,
        fmt::format("the bench's J = {:.4g} kg·m² is less than the motor's rotor alone ({:.4g} kg·m²): the "
                    "friction numbers are wrong — fix [bench] inertia in the bench file",
                    J, *cfg.datasheet->rotor_inertia_kg_m2));
    f.value = J;
    f.reference = *cfg.datasheet->rotor_inertia_kg_m2;
    f.reference_name = "datasheet";
    f.unit = "kg*m^2";
    v.findings.push_back(std::move(f));
  }
  lab_rules(fit, best, th, v.findings);
  // A doubt about the numbers themselves (units, a model that misses): nothing is judged OK on them.
  for (const auto& d : fit.doubts) v.findings.push_back(note_finding("fit", HealthLevel::check, "doubtful fit: " + d));

  for (const auto& f : v.findings) v.level = std::max(v.level, f.level);
  std::vector<const HealthFinding*> flagged;
  for (const auto& f : v.findings)
    if (f.level != HealthLevel::ok) flagged.push_back(&f);
  std::stable_sort(flagged.begin(), flagged.end(), [](auto* a, auto* b) { return a->level > b->level; });
  std::string reason;
  for (const auto* f : flagged) reason += (reason.empty() ? "" : "; ") + f->reason;
  if (!v.has_reference) {
    const std::string none =
        "not judged: the bench file has no [motor] datasheet (no-load current and torque or speed constant) "
        "and no [baseline], so friction cannot be judged — make a baseline with `spindown baseline`";
    v.reason = reason.empty() ? none : reason + "; " + none;
    if (v.level == HealthLevel::ok) v.level = HealthLevel::not_judged;
  } else if (!reason.empty()) {
    v.reason = reason;
  } else {
    std::string summary;
    for (const auto& f : v.findings)
      if (f.ratio != 0 && f.unit != "s")
        summary += fmt::format("{}{} {} the {}", summary.empty() ? "" : ", ", f.what, times(f.ratio), f.reference_name);
    v.reason = summary.empty() ? "nothing unusual" : "friction as expected: " + summary;
  }
  return v;
}

}  // namespace spindown
