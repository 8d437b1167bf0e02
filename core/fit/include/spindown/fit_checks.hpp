#pragma once
// What a fit's numbers cannot say by themselves: whether the assumptions that make them right
// held. Each check gives words for the default output (never only with -v), the JSON's
// "doubts" and the health verdict, which is never OK while a doubt stands.
//  - units: readings no bench of this kind can produce (a back-EMF far beyond the Arduino's 5 V,
//    a speed no flywheel reaches) mean the unit is wrong; the likely fix is named;
//  - resolution: an extra friction term that changes the fitted curve by less than half the
//    reading's printed step cannot be told from the simpler model, whatever the likelihood of
//    continuous noise says (the print and the ADC quantize);
//  - model miss: the best model's residuals, in bins, lie further from zero than the run's own
//    noise allows: a physical effect is missing (spindown explain names it).
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "spindown/fit.hpp"

namespace spindown {

// The largest back-EMF reading a lab bench produces (V) and the fastest shaft (rad/s, ~28,600
// rpm) a teaching flywheel reaches; beyond them the unit is doubted.
inline constexpr double plausible_max_volts = 30.0;
inline constexpr double plausible_max_omega = 3000.0;

// The readings' quantization step (the smallest change between neighbouring readings, when nearly
// every reading is a whole number of it from the first), 0 when the readings are not quantized.
double reading_step(std::span<const double> values);

// Doubts about the units of a fit's readings (empty when plausible). peak: the largest reading
// of the run; whole_numbers: every reading is a whole number (a converter's raw counts?).
std::vector<std::string> unit_doubts(const RunFit& fit, double peak, bool whole_numbers = false);

// The largest difference, over the times tau (s after the cut), between two fitted models'
// curves in the reading's unit (k: reading per rad/s), or a value at least `enough` as soon as one
// is found.
double largest_curve_difference(const ModelFit& a, const ModelFit& b, std::span<const double> tau, double k,
                                double enough = INFINITY);

// A combined model whose dry friction acts like an offset under max(2 reading steps, this fraction
// of the reading at the cut) is not told from viscous with a zero level that far off (check_fit).
inline constexpr double offset_allowance_fraction = 0.002;

// How far the best model's residuals lie from zero in bins over the moving part of the coast
// (residual_bin samples, fewer on a short run: n/8, at least min_residual_bin), against the noise of
// a bin's mean: the reading noise σ (RunFit::reading_noise; when not given, from the residuals'
// first differences, which the smooth part cancels) over √bin, or what the bins' jumps show when
// the noise is correlated (with honest_noise_bins bins or more), and the reading's step (a bin's
// mean is known no better than step/√12). check_fit doubts the model when the bins' Σz² (each
// counted up to 4²: one stretch at the cut does not decide) stands
// more than misfit_excess_z of its spread √(2·bins) above the bin count.
inline constexpr std::size_t residual_bin = 25;
inline constexpr std::size_t min_residual_bin = 4;
inline constexpr std::size_t honest_noise_bins = 16;
inline constexpr double misfit_excess_z = 5.0;
struct ResidualStructure {
  std::size_t bins = 0;
  std::size_t bin = 0;        // samples per bin
  std::size_t beyond = 0;     // bins further than 4 standard errors from zero
  double chi2 = 0;            // Σ min(z², 16) over the bins (about `bins` for a model that holds)
  double excess_z = 0;        // (chi2 − bins)/√(2·bins)
  double worst_tau_s = 0;     // where the worst bin lies (s after the cut)
  double worst_mean = 0;      // its mean residual (reading unit)
  double sigma = 0;           // the reading noise σ used (reading unit)
  double bin_se = 0;          // a bin mean's standard error
};
ResidualStructure residual_structure(const ModelFit& m, std::span<const double> tau, std::span<const double> y,
                                     std::size_t moving, double k, double step, double sigma = 0);

// All of the above for one fitted run (fit_run calls it last): sets reading_step and doubts,
// and keeps the simpler model as best when the print cannot resolve what the extra term adds.
// tau, y: the fitted samples (y less the zero level), the first `moving` of them before the
// stop; raw: the run's readings as read.
void check_fit(RunFit& fit, std::span<const double> tau, std::span<const double> y, std::size_t moving,
               std::span<const double> raw, double k);

}  // namespace spindown
