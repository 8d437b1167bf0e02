#include "spindown/bounded_refinement.hpp"

#include <exception>
#include <fmt/format.h>
#include <nlopt.hpp>

namespace spindown {
namespace {

struct Callback {
  const RefinementObjective* objective;
  int evals = 0;
  std::exception_ptr error;
};

// NLopt's C++ objective: never let the caller's exception cross it (design §7).
double nlopt_objective(unsigned n, const double* x, double* grad, void* data) {
  auto* cb = static_cast<Callback*>(data);
  try {
    ++cb->evals;
    return (*cb->objective)(std::span<const double>(x, n), grad ? std::span<double>(grad, n) : std::span<double>());
  } catch (...) {
    cb->error = std::current_exception();
    throw nlopt::forced_stop();
  }
}

}  // namespace

std::string refine_bounded(std::vector<double>& x, const RefinementOptions& options,
                           const RefinementObjective& objective, int& evaluations) {
  Callback cb{&objective, 0, nullptr};
  double fmin = 0;
  std::string why;
  try {
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(x.size()));
    opt.set_lower_bounds(options.lower);
    opt.set_upper_bounds(options.upper);
    opt.set_min_objective(nlopt_objective, &cb);
    opt.set_ftol_rel(options.ftol_rel);
    opt.set_xtol_rel(options.xtol_rel);
    opt.set_maxeval(options.max_evaluations);
    const nlopt::result res = opt.optimize(x, fmin);
    if (res == nlopt::MAXEVAL_REACHED)
      why = fmt::format("no convergence within {} evaluations", options.max_evaluations);
  } catch (const nlopt::roundoff_limited&) {
    // at the optimum to machine precision: accept
  } catch (const nlopt::forced_stop&) {
    why = "the objective failed";
    if (cb.error) {
      try {
        std::rethrow_exception(cb.error);
      } catch (const std::exception& e) {
        why = fmt::format("the objective failed: {}", e.what());
      } catch (...) {
      }
    }
  } catch (const std::exception& e) {
    why = fmt::format("NLopt: {}", e.what());
  }
  evaluations += cb.evals;
  return why;
}

}  // namespace spindown
