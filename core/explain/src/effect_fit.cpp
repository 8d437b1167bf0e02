#include "spindown/effect_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <limits>
#include <utility>

#include "spindown/bounded_refinement.hpp"
#include "spindown/effect_simulator.hpp"
#include "spindown/levenberg_marquardt.hpp"
#include "spindown/parameter_covariance.hpp"

namespace spindown {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// Bounds, typical sizes and a simulator for one combination on one run.
struct Setup {
  const std::vector<const Effect*>& effects;
  const EffectFitData& data;
  RunScale scale;
  EffectSimulator sim;
  std::vector<double> lo, hi, typical;

  Setup(const std::vector<const Effect*>& e, const EffectFitData& d)
      : effects(e), data(d), scale(run_scale(d)), sim(e, d.k) {
    const int P = sim.size();
    lo.assign(P, 0.0);
    hi.assign(P, 0.0);
    typical.assign(P, 0.0);
    lo[0] = 1e-6 * scale.omega0;
    hi[0] = 10.0 * scale.omega0 + 1.0;
    typical[0] = scale.omega0;
    for (std::size_t i = 0; i < e.size(); ++i)
      for (int j = 0; j < e[i]->size(); ++j) {
        const EffectParam& p = e[i]->params[j];
        const int at = sim.first_param(i) + j;
        lo[at] = p.lower(scale);
        hi[at] = p.upper(scale);
        typical[at] = p.typical(scale);
      }
  }
  void clamp(std::vector<double>& th) const {
    for (std::size_t j = 0; j < th.size(); ++j) th[j] = std::clamp(th[j], lo[j], hi[j]);
  }
};

// Sample i's weight (1 when the fit is unweighted).
inline double weight_of(const EffectFitData& d, std::size_t i) { return d.weight.empty() ? 1.0 : d.weight[i]; }

// The objective: Σ w·r².
double sse_of(const Setup& s, const std::vector<double>& th, std::vector<double>& model) {
  model.resize(s.data.tau.size());
  s.sim.simulate(th, s.data.tau, model);
  double sse = 0;
  for (std::size_t i = 0; i < model.size(); ++i) {
    const double r = s.data.y[i] - model[i];
    sse += weight_of(s.data, i) * r * r;
  }
  return std::isfinite(sse) ? sse : std::numeric_limits<double>::infinity();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Starting point from the integral form, linear in the amplitudes:
//   ω̂(τ_i) = ω̂(τ_0) − Σ_e a_e·∫_{τ_0}^{τ_i} shape_e(ω̂) dτ,  ω̂ = (y − offset)/k,
// over the samples before the detected stop; no derivative of noisy data is taken. Shape
// parameters (Stribeck speed) are tried on a small grid; negative amplitudes are dropped
// (active set) so the start is feasible.
std::vector<double> integral_start(const Setup& s) {
  const auto& d = s.data;
  std::vector<double> th(s.typical);
  th[0] = s.scale.omega0;
  double offset = 0;
  for (std::size_t e = 0; e < s.effects.size(); ++e) {
    if (s.effects[e]->kind != EffectKind::sensor) continue;
    // The library's sensor effects are additive in their first parameter: start it at the
    // reading at standstill when the run shows one.
    const std::size_t tail = d.tau.size() - std::min(d.moving, d.tau.size());
    const double v = tail >= 5 ? median(std::vector<double>(d.y.begin() + static_cast<std::ptrdiff_t>(d.moving), d.y.end())) : 0.0;
    th[s.sim.first_param(e)] = v;
    offset += v;
  }
  const std::size_t m = std::min(d.moving, d.tau.size());
  std::vector<int> torque;  // effect indices with an amplitude to regress
  for (std::size_t e = 0; e < s.effects.size(); ++e)
    if (s.effects[e]->kind == EffectKind::torque && s.effects[e]->shape) torque.push_back(static_cast<int>(e));
  if (m < torque.size() + 3) return th;

  std::vector<double> w(m);
  for (std::size_t i = 0; i < m; ++i) w[i] = (d.y[i] - offset) / d.k;

  // Grid over the shape parameters (at most one shaped effect varies at a time: the grid of
  // the first shaped effect, others at their typical value).
  std::vector<std::vector<double>> shape_par(s.effects.size());
  int gridded = -1;
  for (int e : torque) {
    const Effect* ef = s.effects[e];
    shape_par[e].assign(th.begin() + s.sim.first_param(e), th.begin() + s.sim.first_param(e) + ef->size());
    if (ef->shape_starts && gridded < 0) gridded = e;
  }
  std::vector<double> grid{0.0};
  if (gridded >= 0) grid = s.effects[gridded]->shape_starts(s.scale);

  double best_sse = std::numeric_limits<double>::infinity();
  std::vector<double> best_th = th;
  const int q = static_cast<int>(torque.size());
  Eigen::MatrixXd a(static_cast<Eigen::Index>(m), q + 1);
  Eigen::VectorXd b(static_cast<Eigen::Index>(m));
  for (std::size_t i = 0; i < m; ++i) {
    a(static_cast<Eigen::Index>(i), 0) = 1.0;
    b[static_cast<Eigen::Index>(i)] = w[i];
  }
  for (double g : grid) {
    if (gridded >= 0 && shape_par[gridded].size() > 1) shape_par[gridded][1] = g;
    for (int c = 0; c < q; ++c) {
      const int e = torque[c];
      double integral = 0, prev = s.effects[e]->shape(shape_par[e].data(), std::max(w[0], 0.0));
      a(0, c + 1) = 0;
      for (std::size_t i = 1; i < m; ++i) {
        const double cur = s.effects[e]->shape(shape_par[e].data(), std::max(w[i], 0.0));
        integral += 0.5 * (prev + cur) * (d.tau[i] - d.tau[i - 1]);
        prev = cur;
        a(static_cast<Eigen::Index>(i), c + 1) = -integral;
      }
    }
    // Normal equations once; the active set works on the small (q+1)² system.
    const Eigen::MatrixXd ata = a.transpose() * a;
    const Eigen::VectorXd atb = a.transpose() * b;
    // Non-negative amplitudes by an active set: drop the most negative, solve again.
    std::vector<bool> active(q, true);
    Eigen::VectorXd sol = Eigen::VectorXd::Zero(q + 1);
    for (int round = 0; round <= q; ++round) {
      std::vector<Eigen::Index> cols{0};
      for (int c = 0; c < q; ++c)
        if (active[c]) cols.push_back(c + 1);
      const auto k = static_cast<Eigen::Index>(cols.size());
      Eigen::MatrixXd sub(k, k);
      Eigen::VectorXd rhs(k);
      for (Eigen::Index r = 0; r < k; ++r) {
        rhs[r] = atb[cols[static_cast<std::size_t>(r)]];
        for (Eigen::Index c = 0; c < k; ++c) sub(r, c) = ata(cols[static_cast<std::size_t>(r)], cols[static_cast<std::size_t>(c)]);
      }
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(sub);
      if (ldlt.info() != Eigen::Success) break;
      const Eigen::VectorXd x = ldlt.solve(rhs);
      if (!x.allFinite()) break;
      sol.setZero();
      for (std::size_t c = 0; c < cols.size(); ++c) sol[cols[c]] = x[static_cast<Eigen::Index>(c)];
      int worst = -1;
      for (int c = 0; c < q; ++c)
        if (active[c] && sol[c + 1] < 0 && (worst < 0 || sol[c + 1] < sol[worst + 1])) worst = c;
      if (worst < 0) break;
      active[worst] = false;
    }
    const double sse = (a * sol - b).squaredNorm();
    if (!(sse < best_sse)) continue;
    best_sse = sse;
    best_th = th;
    // ω at the cut: back from the first sample with the fitted deceleration.
    double r0 = 0;
    for (int c = 0; c < q; ++c) {
      const int e = torque[c];
      const int at = s.sim.first_param(e);
      for (std::size_t j = 1; j < shape_par[e].size(); ++j) best_th[at + j] = shape_par[e][j];
      // A small floor keeps the shape parameters' sensitivities alive.
      best_th[at] = std::max(sol[c + 1], 0.02 * s.typical[at]);
      r0 += best_th[at] * s.effects[e]->shape(shape_par[e].data(), std::max(sol[0], 0.0));
    }
    best_th[0] = sol[0] + r0 * std::max(d.tau[0], 0.0);
  }
  s.clamp(best_th);
  return best_th;
}

// JᵀJ (upper triangle, packed) and Jᵀr of a row-major n×P matrix with P fixed at compile time:
// the accumulators stay in registers, which a general matrix product cannot do for these tall,
// narrow Jacobians.
template <int P>
void normal_fixed(const double* jac, const double* r, std::size_t n, double* jtj_packed, double* jtr) {
  double acc[P * (P + 1) / 2] = {};
  double g_r[P] = {};
  for (std::size_t i = 0; i < n; ++i) {
    const double* g = jac + i * P;
    const double ri = r ? r[i] : 0.0;
    int k = 0;
#pragma GCC unroll 12
    for (int a = 0; a < P; ++a) {
      g_r[a] += g[a] * ri;
#pragma GCC unroll 12
      for (int b = a; b < P; ++b) acc[k++] += g[a] * g[b];
    }
  }
  std::copy(acc, acc + P * (P + 1) / 2, jtj_packed);
  std::copy(g_r, g_r + P, jtr);
}

template <int... Ps>
void normal_dispatch(std::integer_sequence<int, Ps...>, int p, const double* jac, const double* r, std::size_t n,
                     double* packed, double* jtr) {
  ((p == Ps + 1 ? normal_fixed<Ps + 1>(jac, r, n, packed, jtr) : void()), ...);
}

// JᵀJ (and Jᵀr when r is given) of a row-major n×p matrix, p ≤ EffectSimulator::max_params.
void normal_equations(const double* jac, const double* r, std::size_t n, int p, Eigen::MatrixXd& jtj,
                      Eigen::VectorXd& jtr) {
  constexpr int max_p = EffectSimulator::max_params;
  double packed[max_p * (max_p + 1) / 2] = {};
  double g_r[max_p] = {};
  normal_dispatch(std::make_integer_sequence<int, max_p>{}, p, jac, r, n, packed, g_r);
  jtj.resize(p, p);
  jtr.resize(p);
  int k = 0;
  for (int a = 0; a < p; ++a) {
    jtr[a] = g_r[a];
    for (int b = a; b < p; ++b) jtj(a, b) = jtj(b, a) = packed[k++];
  }
}

// What one evaluation leaves: the simulation and its Jacobian (kept at the optimum for the SSE
// and the covariance), and the normal equations from them.
struct Evaluation {
  std::vector<double> model, jac;
  Eigen::MatrixXd jtj;
  Eigen::VectorXd jtr;
};

// Simulates t with its sensitivities into model/jac; JᵀJ, Jᵀr and the SSE from them.
double assemble_normal(const Setup& s, const std::vector<double>& t, Evaluation& ev) {
  const std::size_t n = s.data.tau.size();
  const int P = s.sim.size();
  ev.model.resize(n);
  ev.jac.resize(n * P);
  s.sim.simulate(t, s.data.tau, ev.model, ev.jac);
  thread_local std::vector<double> r, wjac;  // residual and weighted-Jacobian scratch, reused across evaluations
  r.resize(n);
  double sse = 0;
  // Weighted least squares as √w·r and √w·J (ev.jac itself stays the model's sensitivities).
  const bool weighted = !s.data.weight.empty();
  if (weighted) wjac.resize(n * P);
  for (std::size_t i = 0; i < n; ++i) {
    const double sw = weighted ? std::sqrt(s.data.weight[i]) : 1.0;
    r[i] = sw * (s.data.y[i] - ev.model[i]);
    sse += r[i] * r[i];
    if (weighted)
      for (int j = 0; j < P; ++j) wjac[i * P + j] = sw * ev.jac[i * P + j];
  }
  normal_equations(weighted ? wjac.data() : ev.jac.data(), r.data(), n, P, ev.jtj, ev.jtr);
  return std::isfinite(sse) && ev.jtj.allFinite() && ev.jtr.allFinite() ? sse : std::numeric_limits<double>::infinity();
}

// The combination's least squares for the shared Levenberg–Marquardt (levenberg_marquardt.hpp):
// the simulator's exact sensitivities, bounds by projection. Its policy: the damping has a floor
// of 10⁻¹² of JᵀJ's largest diagonal entry; an active set at the bounds; only a step that lowers
// the SSE is taken; converged when every parameter moves less than 10⁻⁷ of itself (or of 10⁻⁶ of
// its typical size) or the SSE gains under 10⁻¹⁰ of itself; at most 60 iterations and 80
// evaluations.
class EffectLeastSquares {
 public:
  using Point = std::vector<double>;
  using State = Evaluation;
  explicit EffectLeastSquares(const Setup& s) : s_(s) {}

  LmPolicy policy() const {
    return {.max_iterations = 60, .max_evaluations = 80, .take_equal = false, .relative_gain = 1e-10};
  }
  double evaluate(const Point& th, State& ev) const { return assemble_normal(s_, th, ev); }
  bool at_minimum(const Point&, const State&, double) const { return false; }
  bool step(const Point& th, const State& ev, double lambda, Point& trial) const {
    const int P = s_.sim.size();
    const Eigen::MatrixXd& jtj = ev.jtj;
    const Eigen::VectorXd& jtr = ev.jtr;
    Eigen::MatrixXd a = jtj;
    Eigen::VectorXd rhs = jtr;
    const double floor = 1e-12 * (jtj.diagonal().maxCoeff() + 1e-300);
    for (int j = 0; j < P; ++j) {
      a(j, j) = jtj(j, j) * (1.0 + lambda) + lambda * floor;
      // A parameter on its bound that the descent direction pushes outward stays there
      // (active set); otherwise projection would make LM stall on rejected steps.
      const bool at_lo = th[j] <= s_.lo[j] && jtr[j] <= 0;
      const bool at_hi = th[j] >= s_.hi[j] && jtr[j] >= 0;
      if (at_lo || at_hi) {
        a.row(j).setZero();
        a.col(j).setZero();
        a(j, j) = 1;
        rhs[j] = 0;
      }
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(a);
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::VectorXd step = ldlt.solve(rhs);
    if (!step.allFinite()) return false;
    trial = th;
    for (int j = 0; j < P; ++j) trial[j] += step[j];
    s_.clamp(trial);
    return true;
  }
  bool negligible(const Point& th, const Point& trial) const {
    for (std::size_t j = 0; j < th.size(); ++j)
      if (std::abs(trial[j] - th[j]) > 1e-7 * std::max(std::abs(th[j]), 1e-6 * s_.typical[j])) return false;
    return true;
  }

 private:
  const Setup& s_;
};

using EffectLm = LmResult<std::vector<double>, Evaluation>;

EffectLm fit_by_lm(const Setup& s, std::vector<double> th) {
  EffectLeastSquares problem(s);
  return levenberg_marquardt(problem, std::move(th));
}

// Bounded L-BFGS (bounded_refinement.hpp) on θ_j / scale_j with the sensitivity gradient, the
// SSE normalised by its value at the start. Returns "" on success or why it failed; th becomes
// the best point found, if it is no worse than th.
std::string refine_with_nlopt(const Setup& s, std::vector<double>& th, int max_evals, int& evals) {
  const int P = s.sim.size();
  std::vector<double> scale(P), x(P);
  RefinementOptions options{.lower = std::vector<double>(P),
                            .upper = std::vector<double>(P),
                            .ftol_rel = 1e-12,
                            .xtol_rel = 1e-10,
                            .max_evaluations = max_evals};
  std::vector<double>& lb = options.lower;
  std::vector<double>& ub = options.upper;
  for (int j = 0; j < P; ++j) {
    scale[j] = std::max(std::abs(th[j]), std::abs(s.typical[j]) * 1e-3) + 1e-300;
    x[j] = th[j] / scale[j];
    lb[j] = s.lo[j] / scale[j];
    ub[j] = s.hi[j] / scale[j];
    x[j] = std::clamp(x[j], lb[j], ub[j]);
  }
  std::vector<double> model;
  const double sse0 = std::max(sse_of(s, th, model), 1e-300);
  // Scratch for the objective: the point, its simulation and sensitivities.
  std::vector<double> point(th), simulated, jac;
  const auto objective = [&](std::span<const double> xs, std::span<double> grad) {
    const std::size_t n = xs.size(), m = s.data.tau.size();
    for (std::size_t j = 0; j < n; ++j) point[j] = xs[j] * scale[j];
    simulated.resize(m);
    jac.resize(grad.empty() ? 0 : m * n);
    s.sim.simulate(point, s.data.tau, simulated, grad.empty() ? std::span<double>() : std::span<double>(jac));
    double sse = 0;
    std::fill(grad.begin(), grad.end(), 0.0);
    for (std::size_t i = 0; i < m; ++i) {
      const double w = weight_of(s.data, i);
      const double r = s.data.y[i] - simulated[i];
      sse += w * r * r;
      for (std::size_t j = 0; j < grad.size(); ++j) grad[j] -= 2 * w * r * jac[i * n + j];
    }
    for (std::size_t j = 0; j < grad.size(); ++j) grad[j] *= scale[j] / sse0;
    return sse / sse0;
  };
  const std::string why = refine_bounded(x, options, objective, evals);
  std::vector<double> cand(P);
  for (int j = 0; j < P; ++j) cand[j] = x[j] * scale[j];
  s.clamp(cand);
  // NLopt returns its best point; keep it only when it is no worse.
  if (sse_of(s, cand, model) <= sse_of(s, th, model)) th = cand;
  return why;
}

// Covariance of θ from the Jacobian (parameter_covariance.hpp): classic s²(JᵀJ)⁻¹ widened per
// parameter to the Newey–West (HAC) variance when residuals are correlated (ripple, quantization).
// Parameters with no influence (a shape parameter whose amplitude is 0) get NaN.
Eigen::MatrixXd covariance(const Setup& s, const std::vector<double>& model, const std::vector<double>& jacv,
                           bool& ok) {
  const std::size_t n = s.data.tau.size();
  const int P = s.sim.size();
  Eigen::MatrixXd cov = Eigen::MatrixXd::Constant(P, P, nan);
  std::vector<int> keep;
  for (int j = 0; j < P; ++j) {
    double norm = 0;
    for (std::size_t i = 0; i < n; ++i) norm += jacv[i * P + j] * jacv[i * P + j];
    if (norm > 0 && std::isfinite(norm)) keep.push_back(j);
  }
  // Weighted least squares: the rows scaled by √w (residual and sensitivities alike).
  std::vector<double> sw(n);
  for (std::size_t i = 0; i < n; ++i) sw[i] = std::sqrt(weight_of(s.data, i));
  const int p = static_cast<int>(keep.size());
  const auto N = static_cast<Eigen::Index>(n);
  ok = false;
  if (p == 0 || N <= p) return cov;
  // Column scaling for conditioning.
  std::vector<double> res(n), js(n * static_cast<std::size_t>(p));
  Eigen::VectorXd cs = Eigen::VectorXd::Zero(p);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < p; ++c) cs[c] += sw[i] * sw[i] * jacv[i * P + keep[c]] * jacv[i * P + keep[c]];
  cs = cs.cwiseSqrt();
  double rss = 0;
  for (std::size_t i = 0; i < n; ++i) {
    res[i] = sw[i] * (s.data.y[i] - model[i]);
    rss += res[i] * res[i];
    for (int c = 0; c < p; ++c) js[i * p + c] = sw[i] * jacv[i * P + keep[c]] / cs[c];
  }
  Eigen::MatrixXd jtj;
  Eigen::VectorXd unused;
  normal_equations(js.data(), nullptr, n, p, jtj, unused);
  // Newey–West: parameter j's long-run variance is that of the series u_j(i) = (inv·score_i)_j,
  // score_i = js_i·r_i.
  const int lags = newey_west_lags(n);
  std::vector<double> u(n);
  const auto long_run = [&](const Eigen::MatrixXd& inv, int j) {
    for (std::size_t i = 0; i < n; ++i) {
      double v = 0;
      for (int c = 0; c < p; ++c) v += inv(j, c) * js[i * p + c];
      u[i] = v * res[i];
    }
    return newey_west_sum(u, lags);
  };
  // An inverse's diagonal past 10¹² (in the scaled columns): a direction the run does not identify.
  const std::optional<Eigen::MatrixXd> widened = hac_covariance(jtj, rss, n, p, long_run, 1e12);
  if (!widened) return cov;
  Eigen::MatrixXd c = cs.cwiseInverse().asDiagonal() * *widened * cs.cwiseInverse().asDiagonal();
  for (int a = 0; a < p; ++a)
    for (int b = 0; b < p; ++b) cov(keep[a], keep[b]) = c(a, b);
  ok = c.allFinite() && p == P;
  return cov;
}

}  // namespace

std::vector<std::string> EffectFit::names() const {
  std::vector<std::string> out;
  for (const Effect* e : effects) out.emplace_back(e->name);
  return out;
}

std::string EffectFit::fit_model() const {
  const std::string l = label();
  return l == "viscous" || l == "coulomb" ? l : l == "viscous+coulomb" ? "combined" : std::string();
}

std::string EffectFit::title() const {
  const std::string fit = fit_model();
  return fit == "combined" ? "combined (viscous+coulomb)" : fit.empty() ? label() : fit;
}

std::string EffectFit::label() const {
  std::string out;
  for (const Effect* e : effects) out += (out.empty() ? "" : "+") + std::string(e->name);
  return out.empty() ? "none" : out;
}

const Parameter* EffectFit::param(std::string_view name) const {
  for (const auto& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

RunScale run_scale(const EffectFitData& d) {
  RunScale s;
  const std::size_t n = d.tau.size();
  if (n == 0) return s;
  double first = 0, ymax = 0;
  for (std::size_t i = 0; i < std::min<std::size_t>(n, 5); ++i) first = std::max(first, d.y[i]);
  for (std::size_t i = 0; i < n; ++i) ymax = std::max(ymax, std::abs(d.y[i]));
  s.omega0 = std::max(first / d.k, 1e-3);
  const std::size_t m = std::clamp<std::size_t>(d.moving, 1, n);
  s.duration_s = std::max(d.tau[m - 1], 0.1);
  s.reading_max = std::max(ymax, 1e-9);
  s.offset_lo = d.offset_lo;
  s.offset_hi = std::max(d.offset_hi, d.offset_lo + 1e-12 * s.reading_max);
  return s;
}

EffectFit fit_effects(const std::vector<const Effect*>& effects, const EffectFitData& data, const EffectFit* warm) {
  EffectFit out;
  out.effects = effects;
  out.n = data.tau.size();
  const Setup s(effects, data);
  const int P = s.sim.size();
  const std::size_t n = data.tau.size();
  if (n < static_cast<std::size_t>(P) + 3 || std::min(data.moving, n) < static_cast<std::size_t>(P) + 2) {
    out.message = fmt::format("{} samples while moving: too few to fit {} parameters", data.moving, P);
    out.theta.assign(P, nan);
    out.sse = out.rmse = out.aic = out.bic = nan;
    return out;
  }

  std::vector<double> model;
  std::vector<double> th = integral_start(s);
  double sse_start = sse_of(s, th, model);
  std::vector<double> th_nested;  // the warm fit's model exactly, new amplitudes ~0
  if (warm && !warm->theta.empty() && std::isfinite(warm->sse)) {
    th_nested = th;
    th_nested[0] = warm->theta[0];
    std::vector<double> th_warm = th;
    th_warm[0] = warm->theta[0];
    for (std::size_t e = 0; e < effects.size(); ++e) {
      const int at = s.sim.first_param(e);
      bool found = false;
      for (std::size_t w = 0; w < warm->effects.size(); ++w)
        if (warm->effects[w] == effects[e]) {
          EffectSimulator ws(warm->effects, data.k);
          for (int j = 0; j < effects[e]->size(); ++j) {
            th_warm[at + j] = warm->theta[ws.first_param(w) + j];
            th_nested[at + j] = th_warm[at + j];
          }
          found = true;
        }
      if (!found) th_nested[at] = effects[e]->kind == EffectKind::sensor ? 0.0 : s.lo[at] + 1e-6 * s.typical[at];
    }
    s.clamp(th_warm);
    s.clamp(th_nested);
    const double sse_warm = sse_of(s, th_warm, model);
    if (sse_warm < sse_start) {
      th = th_warm;
      sse_start = sse_warm;
    }
  }

  EffectLm lm = fit_by_lm(s, th);
  out.evaluations = lm.evals;
  bool warm_is_subset = warm != nullptr;
  if (warm)
    for (const Effect* we : warm->effects) warm_is_subset = warm_is_subset && std::find(effects.begin(), effects.end(), we) != effects.end();
  if (!th_nested.empty() && warm_is_subset && lm.sse > warm->sse * (1 + 1e-9)) {
    // Nested models can only fit better: restart from the smaller model's optimum.
    EffectLm again = fit_by_lm(s, th_nested);
    out.evaluations += again.evals;
    if (again.sse < lm.sse) lm = again;
  }
  th = lm.theta;
  // LM's stopping rule (relative step < 1e-7 or SSE gain < 1e-10) is already tight: a polish
  // would only confirm it. NLopt under bounds takes over when LM did not converge.
  std::string why;
  if (!lm.converged) {
    why = refine_with_nlopt(s, th, 300, out.evaluations);
    if (th != lm.theta) {
      lm.sse = assemble_normal(s, th, lm.state);
    }
  }
  const bool solved = lm.converged || why.empty();

  out.theta = th;
  out.sse = lm.sse;
  out.simulated = std::move(lm.state.model);
  const double dn = static_cast<double>(n);
  double plain = 0;  // Σ r², unweighted: the RMSE in the reading's unit
  for (std::size_t i = 0; i < n; ++i) plain += (data.y[i] - out.simulated[i]) * (data.y[i] - out.simulated[i]);
  out.rmse = std::sqrt(plain / dn);
  const double ll = dn * std::log(std::max(out.sse / dn, 1e-300));
  out.aic = ll + 2.0 * P;
  out.bic = ll + P * std::log(dn);
  out.omega0 = th[0];
  out.t_stop_pred_s = s.sim.stop_time(th);

  bool cov_ok = false;
  const Eigen::MatrixXd cov = covariance(s, out.simulated, lm.state.jac, cov_ok);
  out.converged = solved;
  if (!solved)
    out.message = why;
  else if (!cov_ok)
    out.message = "some parameters are not identifiable from this run (no influence or singular Jacobian)";

  const double J = data.inertia_kg_m2;
  auto se = [&](int j, double factor) {
    const double v = cov(j, j);
    return std::isfinite(v) && v >= 0 ? std::sqrt(v) * std::abs(factor) : nan;
  };
  // The lab's names (effect_fit.hpp): c1/c3 viscous, c2/c4 Coulomb as in spindown fit's models.
  bool viscous = false, coulomb = false;
  for (const Effect* e : effects) viscous = viscous || e->name == "viscous", coulomb = coulomb || e->name == "coulomb";
  int coulomb_at = -1;
  for (std::size_t e = 0; e < effects.size(); ++e)
    if (effects[e]->name == "coulomb") coulomb_at = s.sim.first_param(e);
  for (std::size_t e = 0; e < effects.size(); ++e) {
    const int at = s.sim.first_param(e);
    const std::string_view effect = effects[e]->name;
    for (int j = 0; j < effects[e]->size(); ++j) {
      const EffectParam& p = effects[e]->params[j];
      const double f = p.per_inertia ? J : 1.0;
      const std::string unit = p.unit == "reading" ? data.unit : std::string(p.unit);
      std::string name(p.name);
      if (effect == "viscous") name = coulomb ? "c3" : "c1";
      if (effect == "coulomb") name = viscous ? "c4" : "c2";
      if (effect == "sensor_offset") name = "sensor_offset";
      if (effect == "stribeck" && j == 0) {
        // Reported as the static friction c_s = c_c + (c_s − c_c): what the term rises to at standstill.
        const double var = coulomb_at >= 0 ? cov(coulomb_at, coulomb_at) + cov(at, at) + 2 * cov(coulomb_at, at)
                                           : cov(at, at);
        const double amplitude = th[at] + (coulomb_at >= 0 ? th[coulomb_at] : 0.0);
        out.params.push_back({"c_s", amplitude * J, std::isfinite(var) && var >= 0 ? std::sqrt(var) * J : nan, unit});
        continue;
      }
      out.params.push_back({std::move(name), th[at + j] * f, se(at + j, f), unit});
    }
  }
  out.params.push_back({"omega0", th[0], se(0, 1.0), "rad/s"});
  return out;
}

}  // namespace spindown
