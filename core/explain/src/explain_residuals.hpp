#pragma once
// The residual measures the discrepancy workflow decides by (explain_run's steps): the residual
// of a fit, its systematic part over bins, where it lies, how far a candidate moves the model, and
// the reading's resolution.
#include <cstddef>
#include <span>
#include <vector>

#include "spindown/explain.hpp"
#include "spindown/residual_bins.hpp"

namespace spindown::explain_detail {

// y minus the fit's simulated readings.
std::vector<double> residual_of(std::span<const double> y, const EffectFit& f);
// How much systematic disagreement a residual carries: Σ z² over the bins beyond what noise
// alone gives (K bins → K), judged with a fixed bin noise so models compare fairly.
double systematic_mass(const ResidualBins& b, double bin_se);
// A chi-square excess beyond 3 standard deviations (2K variance) is not noise.
bool mass_significant(double mass, std::size_t bins);
// The measured speed (rad/s) at each reading y: (y − zero level)/k.
std::vector<double> measured_speed(std::span<const double> y, double zero_level, double k);
// The stretches of bins beyond z_thr bin noises, the few that carry most of the disagreement, in
// time order, with the measured speed (speed: per reading) at their ends.
std::vector<Disagreement> locate(const ResidualBins& b, double bin_se, double z_thr, std::span<const double> tau,
                                 std::span<const double> residual, const std::vector<double>& speed, double t_cut);
// The reading's resolution: the smallest step between distinct values (2-decimal prints:
// 0.01 V). Near it, rounding is a deterministic, speed-dependent distortion no effect explains.
double reading_quantum(std::span<const double> y);
// Largest change (bin means of m samples) a candidate makes to the current model's simulation.
double largest_change(const EffectFit& a, const EffectFit& b, std::size_t m);
// Rounding to the reading's step q is noise only where the readings cross steps at unrelated
// phases: in bins where most samples moved a step or more from the one before (a fast coast, or
// noise that dithers). Where they dwell (a staircase, or a converter's step printed at two
// decimals beating with the print's) its error is deterministic, speed-dependent, up to half a
// step, and a model can fit it. How much better b fits than a over the bins where rounding is
// noise: the drop in Σ w·r²/σ² there, each residual less its own mean up to half a step (a
// truncating converter's bias while it dithers), and how many samples those bins hold.
struct RoundingFree {
  double chi2_drop = 0;
  std::size_t samples = 0;
};
RoundingFree evidence_beyond_rounding(std::span<const double> y, std::span<const double> weight, const EffectFit& a,
                                      const EffectFit& b, std::size_t m, double q, double sigma);
bool contains(const std::vector<const Effect*>& v, const Effect* e);
// The model plus one effect, in library order (so names and parameters read the same way).
std::vector<const Effect*> with_effect(const std::vector<const Effect*>& model, const Effect* e);

}  // namespace spindown::explain_detail
