#pragma once
// The discrepancy workflow (design §6): fit the base model (the user's belief), find where its
// simulation and the measurement disagree beyond the noise, try every candidate effect from
// the library, name the one that explains the disagreement, add it, and repeat until nothing
// significant remains. A run that needs nothing more comes back with nothing added.
//
// The samples, the objective and the names are spindown fit's: the run's window less its outliers,
// each sample weighted by 1/σ²(u) from the run's own noise (reading_noise.hpp), so the base model is
// fit's model of the same name (viscous: c1 and ω0 as fit gives them). One difference, said in both
// outputs: fit subtracts the run's zero level, explain keeps the reading's own zero, since a reading
// that does not return to 0 is an effect to name (sensor_offset); when the run shows a standstill
// the offset is bounded by the zero level seen there (between 0 and it, give or take its own
// uncertainty), and with the offset the model is fit's again. With a zero level of 0 (the lab's
// runs) the two are the same model. Two candidates the run cannot tell apart are said to be, never
// chosen between silently; one that is physically impossible (a sensor offset that would read below
// zero at standstill, on a sensor that never reads below zero) is rejected with the reason.
//
// Judging "significant" robustly (ripple, quantization and aliasing make residuals
// correlated): residuals are binned (~0.5 s); the noise of a bin mean is estimated from the
// data itself (bin-to-bin differences of the residual, never below the white-noise value
// from second differences); the information criterion uses an effective sample size
// n_eff = n·σ²_white/(m·σ²_bin) so correlated noise cannot buy an effect.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "spindown/bench.hpp"
#include "spindown/effect_fit.hpp"
#include "spindown/effects.hpp"
#include "spindown/recording.hpp"
#include "spindown/residual_bins.hpp"
#include "spindown/run_window.hpp"
#include "spindown/runs.hpp"

namespace spindown {

struct ExplainOptions {
  BenchParams bench;
  std::vector<const Effect*> base{find_effect("viscous")};  // the lab's belief
  std::vector<const Effect*> candidates;  // empty = the whole library
  double min_delta_bic = 10;    // evidence (effective-sample BIC) needed to add an effect
  double bin_s = 0.5;           // residual bin width for locating the disagreement
  double systematic_z = 4;      // a bin mean this many noise SEs from 0 is systematic
  int max_steps = 4;            // effects added at most
  bool weighted = true;         // as FitOptions::weighted: 1/σ²(u) weights, spindown fit's objective
  bool is_valid(std::string* why) const;
};

// A time (and speed) range where the residual is systematic.
struct Disagreement {
  double t_from_s = 0, t_to_s = 0;      // device time (s), the file's clock
  double tau_from_s = 0, tau_to_s = 0;  // seconds after the cut
  double omega_from = 0, omega_to = 0;  // measured speed (rad/s) at the ends: their bins' mean reading
  double mean_residual = 0;             // measurement − model, reading unit
  double peak_residual = 0;             // largest bin mean (signed)
  double z = 0;                         // peak bin mean / its noise SE
};

// One candidate tried at a step.
struct CandidateTrial {
  std::string effect;
  EffectFit fit;
  double delta_bic = 0;       // effective-sample BIC improvement over the current model (> 0 better)
  double systematic_after = 0;  // share of the systematic disagreement left (binned chi-square excess)
  double change = 0;            // largest change it makes to the model (bin means, reading unit)
  std::string unresolved;       // why the readings cannot tell its change from their own artefacts ("" when they can)
  std::string verdict;        // "added", or why it was rejected
  std::string impossible;     // why its fitted numbers cannot be physical ("" when they can)
};

struct ExplainStep {
  std::string added;
  std::string meaning;              // what the added effect is, worded from its fitted numbers
  std::string signature;            // what a model without it leaves in the residuals, the same way
  double rmse_before = 0, rmse_after = 0;
  double bin_noise = 0;             // noise SE of a bin mean in the residual before the step
  std::vector<Disagreement> where;  // before the step
  std::string overall;              // when no stretch stands out: the residual's spread against the noise
  std::vector<CandidateTrial> trials;
  std::string why;
  // Effects added earlier that the new one made unnecessary (backward check after each step).
  std::vector<std::string> removed;
  // Candidates that fit this run as well as the one added (within 3 in BIC, as many parameters):
  // the run cannot tell them apart; `undecided` says why and what would decide.
  std::vector<std::string> indistinguishable;
  std::string undecided;
  EffectFit fit;  // the model after the step
};

struct ExplainResult {
  Run run;
  BenchParams bench;
  Quantity quantity = Quantity::back_emf_volts;
  std::string unit;                 // the reading's unit
  // Samples used, as spindown fit uses them: seconds after the cut, raw readings, fit's weights
  // (all 1 when unweighted).
  std::vector<double> tau, y, weight;
  double zero_level = 0;            // the run's zero level (Run::zero_level), which spindown fit subtracts
  bool standstill_seen = false;     // the window holds a standstill (the zero level was measured there)
  double offset_lo = 0, offset_hi = 0;  // where a sensor offset may lie (±inf: no standstill, free)
  double reading_noise = 0;         // the reading noise σ (reading_noise_sigma over the coast)
  double bin_noise = 0;             // noise SE of a bin mean in the base residual (≥ σ/√bin_samples)
  std::size_t bin_samples = 0;
  double top_speed = 0;             // the final model's speed at the window's first sample (rad/s)
  EffectFit base;
  std::vector<ExplainStep> steps;
  EffectFit final_fit;
  std::vector<CandidateTrial> final_trials;  // the last round, when every candidate was rejected
  std::vector<Disagreement> remaining;  // systematic ranges left after the last step
  std::string conclusion;               // why the workflow stopped
  bool ok = false;
  std::string message;                  // why the run could not be explained

  double rmse_base() const { return base.rmse; }
  double rmse_final() const { return final_fit.rmse; }
  // A bin mean's noise if the readings' errors were independent: σ/√bin_samples.
  double bin_noise_white() const;
};

ExplainResult explain_run(const Recording& rec, const Run& run, const ExplainOptions& opt);
// The same on raw arrays (t in seconds on the recording's clock), for the live fitter.
ExplainResult explain_run(std::span<const double> t_s, std::span<const double> value, Quantity q, const Run& run,
                          const ExplainOptions& opt);
// The same on the run's window as fit sees it (run_window.hpp: one window for fit and explain),
// with the lowest reading of the whole recording (a sensor that reads zero at rest, below).
ExplainResult explain_run(const RunWindow& window, Quantity q, const Run& run, const ExplainOptions& opt,
                          double lowest_reading);
// The lowest finite reading of a recording (+inf when there is none).
double lowest_reading(std::span<const double> value);

// Residual analysis used by the workflow (bin_residuals: residual_bins.hpp, shared with fit's
// misfit doubt). White noise of the readings from second differences over [0, n) (robust to smooth signal): the
// reading noise σ (reading_noise_sigma), under the name the workflow's tests know.
double white_noise(std::span<const double> y);

// What an effect in a fitted model is, in words from its fitted numbers. Stribeck friction with a
// broad speed scale (ω_s at least a third of top_speed, the fastest the window saw) is not the
// film breaking down near standstill but friction that falls with speed across the whole coast.
std::string effect_meaning(const Effect& effect, const EffectFit& fit, double top_speed);
// What a model without the effect leaves in the residuals, worded the same way.
std::string effect_signature(const Effect& effect, const EffectFit& fit, double top_speed);
// The effect's term with the fit's parameter names ("T = c4", "T = (c_s − c4)·exp(−(ω/ω_s)²)").
std::string effect_term(const Effect& effect, const EffectFit& fit);

}  // namespace spindown
