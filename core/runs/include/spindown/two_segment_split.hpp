#pragma once
// One decision of run finding, on its own: where, in a window [a, b] that holds a cut, the coast
// begins. The window is split in two by least squares: a constant lead-in [a, a+k) (the supply's
// level, zeros, an open pin's level) and a linear coast [a+k, b], for every k at once from prefix
// sums of the lead-in and suffix sums of the line (t relative to t(b)); and where two steps are in
// reach (zeros → supply → back-EMF) the coast follows the later one when it splits a flat plateau
// from the coast by a clear step (beyond five of the line's scatter and 3 % of its level).
#include <cstddef>
#include <vector>

#include "spindown/sample_store.hpp"

namespace spindown {

class TwoSegmentSplit {
 public:
  struct Line {
    double v0 = 0, slope = 0, sd = 0;
  };
  // The window [a, b] of s (its index k runs from 0 at a), its sums in scratch (grown when too
  // small): valid while both are.
  TwoSegmentSplit(const SampleStore& s, std::size_t a, std::size_t b, std::vector<double>& scratch);

  // The coast's line from a+k on: its reading at a+k, slope and residual sd.
  Line post_line(std::size_t k) const;

  // The best split (the coast from a+k) with the lead-in starting at a+kb. The confirming window may straddle a small
  // step (supply → back-EMF), so the split may fall anywhere that leaves a few samples for
  // the line.
  std::size_t best_split(std::size_t kb) const;

  // Two steps in reach (zeros → supply → back-EMF): the coast follows the later one, taken when
  // it splits a flat plateau from the coast by a clear step. From the split k (lead-in from kb),
  // the split the coast follows; kb becomes where its lead-in starts.
  std::size_t later_step(std::size_t& kb, std::size_t k) const;

 private:
  const SampleStore& d;
  std::size_t a, n;
  double tr;
  double *pv, *pvv;                // prefix Σv, Σv² of [a, a+k)
  double *ss, *stt_, *sv_, *stv_;  // suffix Σt, Σt², Σv, Σtv of [a+k, b]
  double svv_all;
};

}  // namespace spindown
