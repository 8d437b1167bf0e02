#pragma once
// Messages as the live lab publishes them, for the tests of spindown watch's table and screen.
#include <string>

#include <spindown/fit_t.hpp>

namespace spindown::test {

// A combined-model fit as spindown-fitter publishes it (flat arrays; model 2 is the best).
inline fit_t fit_msg(const std::string& bench, int run, const std::string& best = "combined") {
  fit_t m{};
  m.bench = bench;
  m.run = run;
  m.residual_unit = "V";
  m.bench_source = "config";
  m.model = {"viscous", "coulomb", "combined"};
  m.nmodels = 3;
  m.rmse = {0.05, 0.02, 0.0123};
  m.r2 = {0.9, 0.99, 0.999};
  m.aic = m.bic = {1, 2, 3};
  m.t_stop_pred_s = {1e9, 8, 7.7};
  m.converged = {true, true, true};
  m.model_samples = {388, 388, 388};
  m.model_message = {"", "", ""};
  m.param_model = {0, 1, 2, 2, 2, 2};
  m.param_name = {"c1", "c2", "c3", "c4", "omega0", "A"};
  m.param_value = {1.4e-6, 1.38e-4, 1.822e-7, 1.139e-4, 450, -5.06};
  m.param_stderr = {1e-8, 1e-6, 1.1e-9, 2e-7, 0.5, 0.01};
  m.param_unit = {"N*m*s/rad", "N*m", "N*m*s/rad", "N*m", "rad/s", "V"};
  m.nparams = static_cast<std::int32_t>(m.param_name.size());
  m.best = best;
  return m;
}

}  // namespace spindown::test
