#pragma once
// How finely a recording resolves its reading, measured from the readings themselves: the one
// scale a run-finding judgement of "evidence" is made in (a rise or a step inside a coast). Not
// the fit's noise model (reading_noise.hpp in fit: σ² against the reading), which is fitted to a
// run already found.
//
//  * white: the sample-to-sample noise, from second differences at lag 1 (they cancel a smooth
//    coast's line and most of its bend);
//  * wander: the largest noise seen at any lag up to max_lag samples: a periodic ripple (an
//    unbalanced wheel, a tyre's once-per-revolution, a commutator) or a slow wander that a
//    lag-1 difference does not see, because neighbouring samples move together. Second
//    differences at lag s are centred on their own median (a coast's steady bend at that lag is
//    no noise) and scaled as a standard deviation (1.4826·MAD/√6: white noise reads the same at
//    every lag; a sinusoid of amplitude A reads about 1.7·A at its half period, its peak to
//    trough).
// Both are robust (medians): a stretch of a different kind (an open pin's hum over part of the
// range, a few dropouts) does not set them.
#include <cstddef>
#include <vector>

namespace spindown {

struct LagNoise {
  double white = 0;   // sample-to-sample noise (standard deviation)
  double wander = 0;  // the largest at any lag up to max_lag (>= white)
  std::size_t wander_lag = 1;  // the lag where wander was largest
};

// v: the readings of one stretch, in order. max_lag: the longest lag looked at (samples); lags
// 1, 2, 4, … up to it, each from at most max_terms second differences spread over the stretch.
LagNoise measure_lag_noise(const std::vector<double>& v, std::size_t max_lag, std::size_t max_terms = 4096);

}  // namespace spindown
