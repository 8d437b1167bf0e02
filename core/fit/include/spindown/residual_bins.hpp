#pragma once
// A fit's residuals averaged over consecutive bins of samples, and what noise a bin's mean carries:
// the one measure of "does the model miss" that fit's misfit doubt and explain's workflow share.

#include <cstddef>
#include <span>
#include <vector>

namespace spindown {

struct ResidualBins {
  std::size_t m = 0;                 // samples per bin
  std::vector<std::size_t> first;    // first sample of each bin
  std::vector<double> mean;          // mean residual per bin
  double white = 0;                  // white-noise σ of one reading
  double from_jumps = 0;             // a bin mean's noise from bin-to-bin jumps (0: under 4 jumps)
  double bin_se = 0;                 // noise SE of a bin mean: max(white/√m, from_jumps)
};

// Bins of m samples (a short last bin joins the one before it). A bin mean's noise is measured
// from the data too: the jumps between neighbouring bins (a smooth misfit barely changes from one
// bin to the next; noise that is correlated over a few samples, a sensor's filter, does), never
// below the white-noise value σ/√m.
ResidualBins bin_residuals(std::span<const double> residual, std::size_t m, double white_sigma);

}  // namespace spindown
