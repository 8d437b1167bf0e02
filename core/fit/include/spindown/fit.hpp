#pragma once
// Fitting the lab's friction models to one run, with the stop modelled and ω0 free.
//   viscous   T = c1·ω        ω = ω0·e^(−c1 τ/J)                        (never stops)
//   coulomb   T = c2          ω = max(ω0 − c2 τ/J, 0)
//   combined  T = c3·ω + c4   ω = max(−c4/c3 + (ω0 + c4/c3)·e^(−c3 τ/J), 0)
// τ is time since the cut; the reading is zero_level + k·ω (k = K_b for volts). Weighted least
// squares: Coulomb in closed form (a scan over the stop), viscous by Newton over c1/J with ω0
// projected out, combined by Levenberg–Marquardt from the integral form's linear solution (NLopt
// under bounds as the fallback); standard errors from the Jacobian at the optimum (widened when
// residuals are correlated).
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/recording.hpp"
#include "spindown/run_window.hpp"
#include "spindown/runs.hpp"

namespace spindown {

enum class ModelKind { viscous, coulomb, combined };
std::string_view model_name(ModelKind k);
std::optional<ModelKind> parse_model(std::string_view name);
inline constexpr ModelKind all_models[] = {ModelKind::viscous, ModelKind::coulomb, ModelKind::combined};

struct Parameter {
  std::string name;   // c1…c4, omega0, A, B, C
  double value = 0;   // SI (curve constants in the reading's unit and seconds)
  double std_error = 0;  // one standard error, same unit ("stderr" in JSON)
  std::string unit;   // "N*m*s/rad", "N*m", "rad/s", "V", "1/s", …
  double bench_error = 0;  // standard uncertainty from J's and K_b's own (BenchParams::*_rel_error)
};

struct ModelFit {
  ModelKind kind = ModelKind::combined;
  std::vector<Parameter> params;  // friction coefficients, omega0, then the seed's curve constants
  double omega0 = 0;              // rad/s at the cut
  double rate = 0;                // c_viscous/J (1/s), 0 for coulomb
  double decel = 0;               // c_coulomb/J (rad/s²), 0 for viscous
  double rmse = 0;                // in the reading's unit
  double r2 = 0, aic = 0, bic = 0;
  double t_stop_pred_s = 0;       // predicted stop, seconds after the cut (inf if never)
  std::size_t n = 0;              // samples fitted
  int evaluations = 0;
  bool converged = false;
  double wsse = 0;                // weighted sum of squared residuals (the weights average 1)
  // χ² of the weighted fit against the run's own noise model (reading_noise.hpp), per degree of
  // freedom: about 1 when the model and the noise model hold; NaN when the noise is not known.
  double reduced_chi2 = std::numeric_limits<double>::quiet_NaN();
  // Correlation of the fitted parameters (omega0, then the model's friction coefficients), row
  // by row; empty when the covariance is not known.
  std::vector<std::string> correlated;
  std::vector<double> correlation;
  std::string message;            // why it did not converge, etc.

  const Parameter* param(std::string_view name) const;
  double omega_at(double tau) const;  // model speed (rad/s) at τ seconds after the cut
};

struct FitOptions {
  BenchParams bench;
  std::vector<ModelKind> models{all_models[0], all_models[1], all_models[2]};
  // Weight each sample by 1/σ²(u), σ² estimated from the run (reading_noise.hpp); false: the
  // lab's unweighted least squares.
  bool weighted = true;
  bool is_valid(std::string* why) const;
};

struct RunFit {
  Run run;
  BenchParams bench;
  Quantity quantity = Quantity::back_emf_volts;
  std::vector<ModelFit> models;
  std::string best;         // model name with the lowest BIC among converged fits, unless the
                            // reading's step cannot resolve what the extra term adds (fit_checks.hpp)
  std::string best_reason;  // why, in words (ΔBIC, RMSE)
  double reading_step = 0;  // the readings' quantization step (0: not quantized)
  // The reading noise σ of the coast (reading_noise.hpp: second differences of the readings before
  // the stop), in the reading's unit: the noise figure every output names.
  double reading_noise = 0;
  // Why the numbers should not be trusted as they stand (units, a model that misses), in words for
  // the default output; empty when nothing is doubted (fit_checks.hpp).
  std::vector<std::string> doubts;
  const ModelFit* model(ModelKind k) const;
};

// Fits the chosen models to samples [run.cut_index, run.end_index) of rec.
RunFit fit_run(const Recording& rec, const Run& run, const FitOptions& opt);

// The same on raw arrays (t in seconds on the recording's clock), for the live fitter.
RunFit fit_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
               const FitOptions& opt);

// The same on a window already made (run_window.hpp), which explain may share: its weights are
// used as they are (window.weighted(), not opt.weighted).
RunFit fit_run(const RunWindow& window, Quantity q, const Run& run, const FitOptions& opt);

}  // namespace spindown
