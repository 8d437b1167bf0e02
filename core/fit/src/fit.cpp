#include "spindown/fit.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <memory>

#include "coulomb_scan.hpp"
#include "fit_covariance.hpp"
#include "spindown/fit_checks.hpp"
#include "fit_evaluator.hpp"
#include "fit_family.hpp"
#include "fit_lm.hpp"
#include "fit_refinement.hpp"
#include "fit_start.hpp"
#include "spindown/reading_noise.hpp"
#include "spindown/run_window.hpp"
#include "viscous_projection.hpp"

namespace spindown {

using namespace friction;

namespace {

Parameter make_param(std::string name, double value, double se, std::string unit) {
  return {std::move(name), value, se, std::move(unit)};
}

ModelFit fit_model(ModelKind kind, std::span<const double> tau, std::span<const double> y, std::size_t moving,
                   double k, const BenchParams& bench, std::string_view runit, Evaluator* evaluator,
                   const IntegralForm& form, const Theta* start = nullptr) {
  ModelFit out;
  out.kind = kind;
  out.n = tau.size();
  const Family fam = family_of(kind);
  const int p = fam.size();
  if (moving < static_cast<std::size_t>(p) + 2 || tau.size() < static_cast<std::size_t>(p) + 2) {
    out.message = fmt::format("{} samples while moving: too few to fit {} parameters", moving, p);
    return out;
  }

  // Start: the integral form; guard it into the feasible region (α, β ≥ 0, u0 > 0).
  Theta th = start ? *start : integral_start(fam, form);
  const double y_first = *std::max_element(y.begin(), y.begin() + std::min<std::size_t>(moving, 5));
  if (!(th.u0 > 0) || !std::isfinite(th.u0)) th.u0 = std::max(y_first, 1e-6);
  const double span_s = std::max(tau[moving - 1], 1e-3);
  if (!start && fam.alpha_free && !(th.alpha > 0)) th.alpha = fam.beta_free ? 1e-3 / span_s : 1.0 / span_s;
  if (!start && fam.beta_free && !(th.beta > 0)) th.beta = fam.alpha_free ? 1e-3 * th.u0 / span_s : th.u0 / span_s;

  Evaluator& eval = *evaluator;
  // Viscous and Coulomb have direct solutions (one parameter by Newton, or none); LM for the
  // combined model and whenever a direct solution declines.
  std::optional<Theta> direct;
  if (kind == ModelKind::viscous) direct = viscous_by_projection(eval, th.alpha, out.evaluations);
  if (kind == ModelKind::coulomb) direct = coulomb_by_line_scan(eval, moving, out.evaluations);
  bool solved = direct.has_value();
  if (direct) {
    th = *direct;
  } else {
    const LmOutcome lm = levenberg_marquardt(fam, th, eval);
    out.evaluations += lm.evals;
    th = lm.theta;
    solved = lm.converged;
  }
  std::string why;
  if (!solved) {
    // Fallback: NLopt's L-BFGS under bounds on scaled parameters, from LM's best point.
    why = refine_with_nlopt(fam, tau, eval, th, out.evaluations);
    solved = why.empty();
  }
  // The likelihood is the weighted one (weights average 1, so with equal weights it is the
  // classic n·log(SSE/n)); RMSE and R² are in the reading's own unit.
  const Covariance cv = covariance(fam, th, eval);  // first: its Jacobian pass serves the sums below
  const double wsse = eval(fam, th);
  const double sse = eval.plain_sse(fam, th);
  const double n = static_cast<double>(tau.size());
  const double sst = eval.total_sum_sq();
  out.rmse = std::sqrt(sse / n);
  out.r2 = sst > 0 ? 1.0 - sse / sst : nan;
  const double ll = n * std::log(std::max(wsse / n, 1e-300));
  out.aic = ll + 2.0 * p;
  out.bic = ll + p * std::log(n);
  out.t_stop_pred_s = stop_time(th);
  out.omega0 = th.u0 / k;
  out.rate = th.alpha;
  out.decel = th.beta / k;

  out.wsse = wsse;
  if (cv.ok) {
    // Correlations of (omega0, the friction coefficients): each is a positive multiple of one of
    // the free parameters (u0, α, β), so their correlations are those of θ.
    out.correlated = {"omega0"};
    if (fam.alpha_free) out.correlated.emplace_back(kind == ModelKind::combined ? "c3" : "c1");
    if (fam.beta_free) out.correlated.emplace_back(kind == ModelKind::combined ? "c4" : "c2");
    for (int i = 0; i < p; ++i)
      for (int j = 0; j < p; ++j) {  // from the upper triangle, so the matrix is exactly symmetric
        const int a = std::min(i, j), b = std::max(i, j);
        const double d = std::sqrt(cv.cov(a, a) * cv.cov(b, b));
        out.correlation.push_back(a == b ? 1.0 : d > 0 ? cv.cov(a, b) / d : nan);
      }
  }
  out.converged = solved && cv.ok;
  if (!solved) out.message = why;
  else if (!cv.ok) out.message = "parameters are not identifiable from this run (singular Jacobian)";
  const Eigen::Matrix3d& c = cv.cov;
  const double J = bench.inertia_kg_m2;
  const auto se = [&](double du0, double dal, double dbe) { return cv.ok ? delta_se(fam, c, du0, dal, dbe) : nan; };
  const std::string ru(runit), rate_unit = ru + "/s";
  switch (kind) {
    case ModelKind::viscous:
      out.params = {make_param("c1", th.alpha * J, se(0, J, 0), "N*m*s/rad"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", th.u0, se(1, 0, 0), ru), make_param("B", th.alpha, se(0, 1, 0), "1/s")};
      break;
    case ModelKind::coulomb:
      out.params = {make_param("c2", th.beta * J / k, se(0, 0, J / k), "N*m"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", -th.beta, se(0, 0, 1), rate_unit), make_param("B", th.u0, se(1, 0, 0), ru)};
      break;
    case ModelKind::combined: {
      // y = A + B·e^(Cτ): A = −β/α, B = u0 + β/α, C = −α (the lab's seed curve). With α at its
      // bound 0 the curve is Coulomb's straight line and A, B are infinite: no number to give.
      const double a = th.alpha;
      const bool curve = a > 0;
      const auto curve_se = [&](double du0, double dal, double dbe) { return curve ? se(du0, dal, dbe) : nan; };
      out.params = {make_param("c3", th.alpha * J, se(0, J, 0), "N*m*s/rad"),
                    make_param("c4", th.beta * J / k, se(0, 0, J / k), "N*m"),
                    make_param("omega0", out.omega0, se(1 / k, 0, 0), "rad/s"),
                    make_param("A", curve ? -th.beta / a : -inf, curve_se(0, th.beta / (a * a), -1 / a), ru),
                    make_param("B", curve ? th.u0 + th.beta / a : inf, curve_se(1, -th.beta / (a * a), 1 / a), ru),
                    make_param("C", -th.alpha, se(0, -1, 0), "1/s")};
      break;
    }
  }
  return out;
}

}  // namespace

std::string_view model_name(ModelKind k) {
  switch (k) {
    case ModelKind::viscous: return "viscous";
    case ModelKind::coulomb: return "coulomb";
    case ModelKind::combined: return "combined";
  }
  return "?";
}

std::optional<ModelKind> parse_model(std::string_view name) {
  for (ModelKind k : all_models)
    if (model_name(k) == name) return k;
  return std::nullopt;
}

const Parameter* ModelFit::param(std::string_view name) const {
  for (const auto& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

double ModelFit::omega_at(double tau) const {
  const Family f = family_of(kind);
  const Theta th{omega0, rate, decel};  // in ω units (k = 1)
  return reading(f, th, std::max(tau, 0.0), nullptr);
}

const ModelFit* RunFit::model(ModelKind k) const {
  for (const auto& m : models)
    if (m.kind == k) return &m;
  return nullptr;
}

bool FitOptions::is_valid(std::string* why) const {
  if (!bench.is_valid(why)) return false;
  if (models.empty()) {
    if (why) *why = "no model chosen";
    return false;
  }
  return true;
}

RunFit fit_run(const RunWindow& window, Quantity q, const Run& run, const FitOptions& opt) {
  RunFit out;
  out.run = run;
  out.bench = opt.bench;
  out.quantity = q;
  const double k = value_per_rad_per_s(q, opt.bench.kb_v_s_per_rad);
  const std::span<const double> tau = window.tau(), y = window.y(), weight = window.weight();
  const std::size_t n = window.size(), moving = window.moving();
  const std::string_view runit = quantity_unit(q);
  out.reading_noise = window.reading_noise();
  const ReadingNoise& noise = window.noise();
  Evaluator eval(tau, y, weight);  // one workspace for every model of the run
  const IntegralForm form = integral_form(tau, y, moving);
  for (ModelKind kind : opt.models)
    out.models.push_back(fit_model(kind, tau, y, moving, k, opt.bench, runit, &eval, form));
  // The combined model nests the other two, but from a poor start LM can come to rest on the bound
  // α = 0 or β = 0 short of their fit (seen on a damaged log: RMSE 0.34 V beside Coulomb's 0.08 V).
  // Then it starts again from the better nested fit: LM takes only steps that lower the SSE, so the
  // combined fit ends at least as good as both.
  for (auto& m : out.models) {
    if (m.kind != ModelKind::combined || !m.converged) continue;
    // Compared by n·log(SSE/n), the AIC without its 2p: no pass over the data unless LM starts again.
    const ModelFit* from = nullptr;
    double least = m.aic - 6;
    for (const auto& nested : out.models)
      if (nested.kind != ModelKind::combined && nested.converged && nested.aic - 4 < least)
        least = nested.aic - 4, from = &nested;
    if (!from) continue;
    const Theta restart{from->omega0 * k, from->rate, from->decel * k};
    ModelFit again = fit_model(ModelKind::combined, tau, y, moving, k, opt.bench, runit, &eval, form, &restart);
    again.evaluations += m.evaluations;
    if (again.converged && again.aic < m.aic) m = std::move(again);
  }

  // J and K_b's own uncertainty in each coefficient: c = α·J (c1, c3) or β·J/k (c2, c4) and
  // ω0 = u0/k, where k is K_b for a back-EMF reading and a constant for a speed.
  {
    const double rj = opt.bench.inertia_rel_error, rk = q == Quantity::back_emf_volts ? opt.bench.kb_rel_error : 0.0;
    for (auto& m : out.models)
      for (auto& p : m.params) {
        const double rel = p.name == "c1" || p.name == "c3"   ? rj
                           : p.name == "c2" || p.name == "c4" ? std::hypot(rj, rk)
                           : p.name == "omega0"               ? rk
                                                              : 0.0;
        p.bench_error = std::fabs(p.value) * rel;
      }
  }

  // χ² per degree of freedom against the run's noise model: the weights are 1/σ²(u) scaled to
  // average 1, so Σ r²/σ² = wsse · mean(1/σ²).
  if (noise.known) {
    // mean(1/σ²) over every 8th reading: a scale, which that estimates well enough.
    double inv = 0;
    std::size_t seen = 0;
    for (std::size_t i = 0; i < n; i += 8, ++seen) inv += 1.0 / std::max(noise.variance(y[i]), 1e-300);
    inv /= static_cast<double>(std::max<std::size_t>(seen, 1));
    for (auto& m : out.models) {
      const double dof = static_cast<double>(n) - static_cast<double>(family_of(m.kind).size());
      if (m.converged && dof > 0) m.reduced_chi2 = m.wsse * inv / dof;
    }
  }

  // Best model: lowest BIC among converged fits (BIC penalises the extra parameter).
  const ModelFit* best = nullptr;
  const ModelFit* second = nullptr;
  for (const auto& m : out.models) {
    if (!m.converged) continue;
    if (!best || m.bic < best->bic) {
      second = best;
      best = &m;
    } else if (!second || m.bic < second->bic) {
      second = &m;
    }
  }
  if (best) {
    out.best = std::string(model_name(best->kind));
    if (second) {
      const double dbic = second->bic - best->bic;
      const char* strength = dbic > 10 ? "very strong" : dbic > 6 ? "strong" : dbic > 2 ? "positive" : "weak";
      out.best_reason = fmt::format("lowest BIC, {:.1f} below {} ({} evidence); RMSE {:.4g} {} vs {:.4g} {}", dbic,
                                    model_name(second->kind), strength, best->rmse, runit, second->rmse, runit);
    } else {
      out.best_reason = out.models.size() == 1 ? "the only model asked for" : "the only model that converged";
    }
  }
  check_fit(out, tau, y, moving, window.readings(), k);
  return out;
}

RunFit fit_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
               const FitOptions& opt) {
  return fit_run(RunWindow(t_s, value, run, opt.weighted), q, run, opt);
}

RunFit fit_run(const Recording& rec, const Run& run, const FitOptions& opt) {
  return fit_run(rec.t_s, rec.value, rec.quantity, run, opt);
}

}  // namespace spindown
