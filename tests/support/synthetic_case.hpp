#pragma once
// A generated run with the Run its truth gives, so a fit is tested apart from segmentation.
#include <cmath>
#include <cstddef>
#include <vector>

#include "spindown/runs.hpp"
#include "spindown/synthetic_run.hpp"

namespace spindown::testing {

// A Run built from the generator's truth, so the fit is tested apart from segmentation.
inline Run run_from_truth(const SyntheticRun& s, const std::vector<double>& t, double tail_s = 2.0) {
  Run run;
  run.number = 1;
  const double tc = s.t_cut_ms / 1000.0;
  std::size_t i = 0;
  while (i < t.size() && t[i] < tc) ++i;
  run.cut_index = i;
  run.t_cut_s = i > 0 ? 0.5 * (t[i - 1] + t[i]) : t[i];
  run.stopped = s.stopped;
  while (i < t.size() && t[i] < tc + s.t_stop_s) ++i;
  run.stop_index = i;
  run.t_stop_s = i < t.size() ? t[i] : NAN;
  while (i < t.size() && t[i] < tc + s.t_stop_s + tail_s) ++i;
  run.end_index = i;
  if (!run.stopped) run.stop_index = run.end_index;
  return run;
}

struct Case {
  SyntheticRunSpec spec;
  SyntheticRun run;
  std::vector<double> t;
  Run seg;
};

inline Case make_case(const SyntheticRunSpec& spec) {
  Case c{spec, make_synthetic_run(spec), {}, {}};
  c.t.reserve(c.run.t_ms.size());
  for (double ms : c.run.t_ms) c.t.push_back(ms / 1000.0);
  c.seg = run_from_truth(c.run, c.t);
  return c;
}

}  // namespace spindown::testing
