#pragma once
// One decision of run finding, on its own: what came before a cut (its lead-in), and so what the
// reading was before the supply was cut. The cut's split (two_segment_split.hpp) gives a lead-in
// [a, pre_end) and the coast's line after it; the lead-in is then described (its level, spread,
// sample-to-sample noise, highest reading and trend) and named by comparing it with the coast in
// the coast's own noise:
//   "powered"  no step at the cut beyond either side's noise (a speed reading: the motor's speed
//              runs on into the coast);
//   "supply"   a step down at the cut (the supply's voltage, then the back-EMF);
//   "zeros"    a step up from about zero (A0 read nothing until the motor was connected);
//   "floating" a lead-in far rougher than the coast (an open pin's hum, the handout's step 6) or
//              a wandering level;
//   "none"     fewer than three samples before the cut.
#include <cstddef>
#include <string>

#include "spindown/sample_store.hpp"

namespace spindown {

// A cut found in a window, with its lead-in and what is known of both.
struct CutSplit {
  std::size_t a = 0, cut_index = 0, pre_end = 0, npre = 0;
  double t_cut_s = 0, v0 = 0, sd_post = 0, post_slope = 0;
  double pre_mean = 0, pre_sd = 0, pre_max = 0;
  double pre_rough = 0;   // the lead-in's sample-to-sample noise (rough_sd)
  double post_rough = 0;  // the coast's (rough_sd: a bounce sample or two at its start do not set it)
  bool pre_declining = false;  // the lead-in falls at a good part of the coast's rate, into it: more coast
  bool pre_flat = false;       // lead-in slope shown to be well below the coast's
  bool clipped = false;
  std::size_t pin_first = 0, pin_last = 0;
  double pin_level = 0;
};

// The lead-in [sp.a, sp.pre_end) of s described into sp: npre, pre_mean, pre_sd, pre_max, pre_rough,
// pre_declining, pre_flat (from the coast's v0, sd_post, post_slope and clipped already in sp).
void describe_lead_in(const SampleStore& s, CutSplit& sp);

// The lead-in's name (above), from sp described.
std::string classify_lead_in(const CutSplit& sp);

}  // namespace spindown
