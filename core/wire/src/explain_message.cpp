#include "spindown/explain_message.hpp"

#include "spindown/explain_report.hpp"

namespace spindown {

explain_t to_explain_message(const ExplainResult& r, const std::string& bench, std::int64_t utime) {
  explain_t m{};
  m.utime = utime;
  m.bench = bench;
  m.run = r.run.number;
  for (const auto& name : r.base.names()) m.base.push_back(name);
  m.nbase = static_cast<std::int32_t>(m.base.size());
  m.rmse_base = r.rmse_base();
  m.rmse_final = r.rmse_final();
  m.noise_level = r.reading_noise;  // the reading noise σ
  for (std::size_t s = 0; s < r.steps.size(); ++s) {
    const ExplainStep& step = r.steps[s];
    m.step_added.push_back(step.added);
    m.step_rmse_before.push_back(step.rmse_before);
    m.step_rmse_after.push_back(step.rmse_after);
    m.step_why.push_back(step.why);
    for (const Disagreement& d : step.where) {
      m.where_step.push_back(static_cast<std::int32_t>(s));
      m.where_t_from_s.push_back(d.t_from_s);
      m.where_t_to_s.push_back(d.t_to_s);
      m.where_mean_residual.push_back(d.mean_residual);
    }
  }
  m.nsteps = static_cast<std::int32_t>(m.step_added.size());
  m.nwhere = static_cast<std::int32_t>(m.where_step.size());
  for (const auto& name : r.final_fit.names()) m.final_effects.push_back(name);
  m.nfinal = static_cast<std::int32_t>(m.final_effects.size());
  for (const Parameter& p : r.final_fit.params) {
    m.param_name.push_back(p.name);
    m.param_value.push_back(p.value);
    m.param_stderr.push_back(p.std_error);
    m.param_unit.push_back(p.unit);
  }
  m.nparams = static_cast<std::int32_t>(m.param_name.size());
  m.story = r.ok ? format_explain(r) : "could not explain this run: " + r.message;
  return m;
}

}  // namespace spindown
