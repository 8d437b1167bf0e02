#pragma once
// Estimating any combination of effects by output error: simulate the run (EffectSimulator)
// and minimise the squared difference to the readings over ω0 and every effect parameter,
// under bounds. Start: a regression of the integral form of the ODE on the candidate terms
// (ω(τ) = ω(τ₀) − Σ a_e·∫ shape_e(ω) dτ, shape parameters on a small grid), or a warm start
// from a nested model's optimum, whichever simulates closer. Refinement: Levenberg–Marquardt
// on the exact sensitivities with the bounds enforced by projection; NLopt (LD_LBFGS,
// bounded, scaled) takes over when LM does not converge. Standard errors from the
// Jacobian at the optimum, widened Newey–West style when the residuals are correlated.
//
// ω0 is estimated at the detected cut. The cut time itself is not estimated separately: for
// an autonomous ODE fitted on post-cut samples a shift of the time origin and a change of ω0
// give the same curve, so the pair is not identifiable; the cut stays at the detector's value.
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "spindown/effects.hpp"
#include "spindown/fit.hpp"

namespace spindown {

// One run's samples as the fit sees them (explain gives spindown fit's samples and weights: each
// sample weighted by 1/σ²(u) from the run's own noise).
struct EffectFitData {
  std::span<const double> tau;  // seconds since the cut
  std::span<const double> y;    // raw readings (no zero level removed: a sensor offset is an effect)
  std::span<const double> weight;  // one per sample, averaging 1 (reading_noise.hpp); empty: unweighted
  std::size_t moving = 0;       // samples before the detected stop (all when it never stopped)
  double k = 1;                 // reading per rad/s
  double inertia_kg_m2 = 1;     // J, to report torque coefficients in SI
  std::string unit = "V";       // the reading's unit
  // Where a sensor offset may lie (reading unit; RunScale::offset_lo, offset_hi): between 0 and the
  // zero level seen at standstill, widened by that level's own uncertainty, when the run shows one.
  double offset_lo = -std::numeric_limits<double>::infinity();
  double offset_hi = std::numeric_limits<double>::infinity();
};

// The reported names are the lab's, as spindown fit gives them: the viscous coefficient is c1
// alone and c3 beside Coulomb friction, the Coulomb torque c2 alone and c4 beside viscous
// friction (the combined model); the extra effects keep their own: c_s (static friction, Stribeck:
// c_c plus the Stribeck amplitude), w_s (Stribeck speed, text ω_s), c_w (windage), sensor_offset;
// omega0 (text ω0) the speed at the cut.

struct EffectFit {
  std::vector<const Effect*> effects;
  std::vector<double> theta;        // internal: ω0, then each effect's parameters
  std::vector<Parameter> params;    // SI: each effect's parameters, then omega0, then derived (c_s)
  std::vector<double> simulated;    // model reading at each sample
  double omega0 = 0;                // rad/s at the cut
  // sse: the objective, Σ w·r² (the weights average 1; Σ r² unweighted), which aic and bic use;
  // rmse: √(Σ r²/n), unweighted, in the reading's unit (as spindown fit's).
  double sse = 0, rmse = 0, aic = 0, bic = 0;
  double t_stop_pred_s = 0;         // seconds after the cut, inf if it never stops
  std::size_t n = 0;
  int evaluations = 0;
  bool converged = false;
  std::string message;              // why not converged, identifiability, …

  std::vector<std::string> names() const;  // effect names
  std::string label() const;               // "viscous+coulomb"
  // spindown fit's name for the same model ("viscous", "coulomb", "combined"), "" when it has none.
  std::string fit_model() const;
  // The model as people read it: fit's name, with the effects when they say more
  // ("combined (viscous+coulomb)", "viscous+coulomb+stribeck").
  std::string title() const;
  const Parameter* param(std::string_view name) const;
};

RunScale run_scale(const EffectFitData& data);

// Fits the effects to the data. warm (optional): a fit of a subset of these effects; its
// parameters start the shared ones, and the result is never worse than it (nested models).
EffectFit fit_effects(const std::vector<const Effect*>& effects, const EffectFitData& data,
                      const EffectFit* warm = nullptr);

}  // namespace spindown
