#include "spindown/lead_in.hpp"

#include <algorithm>
#include <cmath>

#include "spindown/reading_scale.hpp"
#include "spindown/window_fit.hpp"

namespace spindown {

void describe_lead_in(const SampleStore& st, CutSplit& sp) {
  // The lead-in [a, pre_end): level, roughness, maximum and trend.
  sp.npre = sp.pre_end - sp.a;
  if (sp.npre < 3) return;
  WindowFit f;
  f.clear(sp.a, st.t(sp.a));
  sp.pre_max = st.v(sp.a);
  for (std::size_t k = sp.a; k < sp.pre_end; ++k) {
    f.add(st.t(k), st.v(k));
    sp.pre_max = std::max(sp.pre_max, st.v(k));
  }
  sp.pre_mean = f.mean();
  sp.pre_rough = rough_sd(st, sp.a, sp.pre_end);
  sp.pre_sd = std::sqrt(std::max(f.svv() / f.n - sp.pre_mean * sp.pre_mean, 0.0));
  // A lead-in falling at a good part of the coast's own rate is more coast: the cut lies
  // further back.
  const double s = f.slope(), sd = f.resid_sd();
  const double s_err = f.sxx() > 0 ? sd / std::sqrt(f.sxx()) : 0.0;
  const bool smooth = sd <= std::max(3.0 * sp.sd_post, 0.02 * std::abs(sp.v0));  // not a wandering pin
  // … and runs into the coast's start without a step: a decline that ends below the coast's
  // start, the reading then jumping up to it (a floating pin's swing, then its connection to the
  // motor), is another signal's, and the cut is the jump.
  const double at_cut = f.mean() + s * (st.t(sp.pre_end) - f.t0 - f.st() / f.n);
  const bool joins = sp.clipped || std::abs(at_cut - sp.v0) <= std::max({5.0 * sp.sd_post, 3.0 * sd, 0.03 * std::abs(sp.v0)});
  sp.pre_declining = sp.npre >= 8 && smooth && joins && s < 0 && -s > 3.0 * s_err &&
                     (sp.clipped || sp.post_slope >= 0 || s <= 0.3 * sp.post_slope);
  sp.pre_flat = sp.npre >= 8 && std::abs(s) + 2.0 * s_err <= 0.3 * std::abs(sp.post_slope);
}

std::string classify_lead_in(const CutSplit& sp) {
  if (sp.npre < 3) return "none";
  const double scale = std::abs(sp.v0);
  const double step = sp.v0 - sp.pre_mean;
  // A lead-in far rougher from sample to sample than the coast is not the motor the coast is read
  // from: an open pin (the handout's step 6) whose hum can hide any step to the back-EMF it is then
  // connected to. (A rise into the cut is smooth, however far it climbs.)
  // The coast's own noise: the smaller of its line's scatter and its sample-to-sample noise (the
  // line's scatter counts the contact bounce at the connection; the second differences do not).
  const double post_noise = sp.post_rough > 0 ? std::min(sp.sd_post, sp.post_rough) : sp.sd_post;
  if (sp.pre_rough > std::max(0.01 * scale, 4.0 * post_noise)) return "floating";
  // No step beyond the noise of either side: a powered motor whose speed is the reading.
  if (std::abs(step) <= std::max({3.0 * sp.sd_post, 4.0 * sp.pre_sd, 0.01 * scale})) return "powered";
  if (step < 0) return "supply";
  if (sp.pre_sd > std::max(0.02 * scale, 3.0 * sp.sd_post)) return "floating";
  if (std::abs(sp.pre_mean) <= 0.1 * scale) return "zeros";
  return "floating";
}

}  // namespace spindown
