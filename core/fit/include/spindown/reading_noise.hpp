#pragma once
// How noisy a coasting run's readings are, as a function of the reading itself. White noise,
// the ADC and the printing step add a constant variance; commutator ripple multiplies the
// reading by (1 + r·sin(…)), adding (r·u)²/2. So σ²(u) = a + b·u², estimated from the data
// alone (no model fit): second differences of the readings remove the smooth coast and keep
// the noise (E[d²] = 6σ² for independent errors, and ripple aliased by the sampling averages
// to the same), regressed on the square of a local mean of the reading. The fit weights each
// sample by 1/σ²(u): an unweighted fit gives the noisy fast start as much say as the quiet
// slow end, which costs precision on c_v and c_c.
#include <cstddef>
#include <span>
#include <vector>

namespace spindown {

struct ReadingNoise {
  double a = 0;      // variance at zero reading (reading unit²)
  double b = 0;      // growth with the reading squared (ripple²/2)
  bool known = false;  // false: too few samples or no positive variance; fit unweighted
  double variance(double u) const { return a + b * u * u; }
};

// σ²(u) from readings y (zero level removed) of one run, cut to end, and the fit weights
// 1/σ²(ū_i), ū the local mean around sample i, scaled so the weights average 1
// over the run (weighted and plain sums of squares stay comparable); all ones when the noise
// is not known (fewer than 32 samples, no variance).
// The ratio of the largest to the smallest variance is capped at max_ratio. Not all error
// averages out: the lab's 10-bit ADC (4.88 mV) printed with 2 decimals (10 mV) rounds odd
// counts down, a pattern of up to ±2.5 mV that drifts with the reading, and weighting the
// slow end 16× (the full σ² range at 1 % ripple) doubles the bias it leaves in c3 and c4.
// Measured over 300 runs from monte_carlo's generator (seed-3v-run1 truth, lab noise, ripple,
// ADC and printing), fitted with each cap (c3 bias, sd in % of the truth): unweighted −0.24,
// 0.68; cap 2: −0.26, 0.63; cap 4: −0.29, 0.61; cap 8: −0.33, 0.59; no cap: −0.57, 0.66. A cap
// of 4 gives the smallest mean squared error; bench/monte_carlo.sh (500 runs) reproduces the
// cap-4 and unweighted rows.
struct NoiseWeights {
  ReadingNoise noise;
  std::vector<double> weight;  // one per reading
};
NoiseWeights weigh_by_noise(std::span<const double> y, double max_ratio = 4.0);
// The same into weight (y.size() values, overwritten): the fit's own buffer, which then needs no
// zeroing or allocation of its own.
ReadingNoise weigh_by_noise_into(std::span<const double> y, std::span<double> weight, double max_ratio = 4.0);

// The reading noise σ: the standard deviation of one reading's error, from the second differences
// of the coasting readings y (E[d²] = 6σ² for independent errors; the smooth coast cancels), that is
// the root mean square of σ(u) over the coast. The one noise figure fit, explain and the report
// name ("reading noise σ"); what a bin of m readings' mean is known to is derived from it (σ/√m,
// widened where the residual is correlated). 0 for fewer than 3 readings.
double reading_noise_sigma(std::span<const double> y);

}  // namespace spindown
