#include "spindown/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <fmt/format.h>
#include <numeric>
#include <optional>

#include "spindown/fit_report.hpp"

namespace spindown {

namespace {

std::string percent(double x) { return fmt::format("{:.0f} %", 100 * x); }

// "2024-10-22" of a day number (wall-clock runs), "run 7" otherwise.
std::string x_words(const std::string& x_unit, double x, double x0_unix) {
  if (x_unit != "day" || x0_unix <= 0) return fmt::format("run {:g}", x);
  const std::time_t t = static_cast<std::time_t>(x0_unix + x * 86400.0);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[16];
  std::strftime(buf, sizeof buf, "%Y-%m-%d", &tm);
  return buf;
}

struct Step {
  double x, before, after, last_before, first_after;
};

// The best split of the points (sorted by x) between two sessions into two weighted levels; a step
// when it leaves χ² at most a quarter of the line's and the levels lie more than drift_sigma of
// their errors (widened by the runs' scatter about them, a motor's run-to-run variation) and
// drift_fraction apart. Two runs a side at least: one stray run is no step.
std::optional<Step> find_step(const CoefficientTrend& t, const std::vector<double>& w, std::size_t n, double chi2_line,
                              const TrendRules& rules) {
  if (n < 4) return std::nullopt;
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return t.x[a] < t.x[b]; });
  const double session_gap = t.x_unit == "day" ? 0.25 : 0.5;
  std::optional<Step> best;
  double best_chi2 = INFINITY, best_se = 0;
  for (std::size_t k = 2; k + 2 <= n; ++k) {  // at least two runs a side
    if (t.x[order[k]] - t.x[order[k - 1]] < session_gap) continue;  // not between sessions
    double sw[2] = {0, 0}, swy[2] = {0, 0};
    for (std::size_t j = 0; j < n; ++j) {
      const int side = j < k ? 0 : 1;
      sw[side] += w[order[j]];
      swy[side] += w[order[j]] * t.value[order[j]];
    }
    const double m0 = swy[0] / sw[0], m1 = swy[1] / sw[1];
    double c2 = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const double r = t.value[order[j]] - (j < k ? m0 : m1);
      c2 += w[order[j]] * r * r;
    }
    if (c2 < best_chi2) {
      best_chi2 = c2;
      best_se = std::sqrt(1 / sw[0] + 1 / sw[1]);
      best = Step{0.5 * (t.x[order[k - 1]] + t.x[order[k]]), m0, m1, t.x[order[k - 1]], t.x[order[k]]};
    }
  }
  if (!best) return std::nullopt;
  const double scatter = std::sqrt(best_chi2 / double(n - 2));
  const double se = best_se * std::max(1.0, scatter);
  const double jump = best->after - best->before;
  if (best_chi2 > 0.25 * chi2_line || std::abs(jump) <= rules.drift_sigma * se ||
      std::abs(jump) < rules.drift_fraction * std::abs(best->before))
    return std::nullopt;
  return best;
}

}  // namespace

CoefficientTrend coefficient_trend(std::string name, std::string unit, std::string x_unit, std::vector<double> x,
                                   std::vector<double> value, std::vector<double> std_error, const TrendRules& rules,
                                   double x0_unix) {
  CoefficientTrend t;
  t.name = std::move(name);
  t.unit = std::move(unit);
  t.x_unit = std::move(x_unit);
  t.x = std::move(x);
  t.value = std::move(value);
  t.std_error = std::move(std_error);
  const std::size_t n = std::min({t.x.size(), t.value.size(), t.std_error.size()});
  const std::string what = t.name == "c3" ? "viscous friction" : t.name == "c4" ? "dry friction" : t.name;
  // Weights 1/σ²; a zero or missing σ gets the median σ so one point cannot take all the weight.
  std::vector<double> sig;
  for (std::size_t i = 0; i < n; ++i)
    if (t.std_error[i] > 0 && std::isfinite(t.std_error[i])) sig.push_back(t.std_error[i]);
  std::sort(sig.begin(), sig.end());
  const double fallback = sig.empty() ? 1.0 : sig[sig.size() / 2];
  double sw = 0, swx = 0, swy = 0;
  std::vector<double> w(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = t.std_error[i] > 0 && std::isfinite(t.std_error[i]) ? t.std_error[i] : fallback;
    w[i] = 1 / (s * s);
    sw += w[i], swx += w[i] * t.x[i], swy += w[i] * t.value[i];
  }
  if (n == 0) {
    t.words = fmt::format("{}: no run with a combined fit", what);
    return t;
  }
  t.mean = swy / sw;
  t.mean_stderr = std::sqrt(1 / sw);
  // Scatter about the mean beyond the runs' own errors widens the mean's error (two runs 400
  // errors apart are not known to a hair), and is said when it is far beyond them.
  if (n >= 2) {
    double chi2_mean = 0;
    for (std::size_t i = 0; i < n; ++i) chi2_mean += w[i] * (t.value[i] - t.mean) * (t.value[i] - t.mean);
    t.scatter = std::sqrt(chi2_mean / static_cast<double>(n - 1));
    t.mean_stderr *= std::max(1.0, t.scatter);
  }
  const bool disagree = t.scatter > rules.disagree_scatter;
  const auto [lo, hi] = std::minmax_element(t.value.begin(), t.value.begin() + static_cast<std::ptrdiff_t>(n));
  const std::string disagreement =
      disagree ? fmt::format("the runs disagree far beyond their errors ({:.3g} to {:.3g} {}, {:.0f}× their standard "
                             "errors apart): check which runs belong to this motor",
                             *lo, *hi, t.unit, t.scatter)
               : "";
  const double xm = swx / sw;
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) sxx += w[i] * (t.x[i] - xm) * (t.x[i] - xm), sxy += w[i] * (t.x[i] - xm) * (t.value[i] - t.mean);
  const auto [xlo, xhi] = std::minmax_element(t.x.begin(), t.x.begin() + static_cast<std::ptrdiff_t>(n));
  const double span = *xhi - *xlo;
  t.enough = n >= rules.min_runs && span > 0 && sxx > 0;
  if (!t.enough) {
    t.words = fmt::format("{}: {} run{}, too few for a trend (need {}){}{}", what, n, n == 1 ? "" : "s",
                          rules.min_runs, disagree ? "; " : "", disagreement);
    return t;
  }
  t.slope = sxy / sxx;
  const double icpt = t.mean - t.slope * xm;
  t.intercept = icpt;
  double chi2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = t.value[i] - (icpt + t.slope * t.x[i]);
    chi2 += w[i] * r * r;
  }
  // Scatter beyond the stated errors (run-to-run variation) widens the slope's error.
  const double birge = n > 2 ? std::max(1.0, std::sqrt(chi2 / static_cast<double>(n - 2))) : 1.0;
  t.slope_stderr = birge / std::sqrt(sxx);
  t.change = t.slope * span;
  t.change_stderr = t.slope_stderr * span;
  if (t.mean != 0) {
    t.relative_change = t.change / std::abs(t.mean);
    t.relative_change_stderr = t.change_stderr / std::abs(t.mean);
  }
  const bool significant = std::abs(t.slope) > rules.drift_sigma * t.slope_stderr;
  t.drifting = significant && std::abs(t.relative_change) >= rules.drift_fraction;
  // Sessions: runs on one day are one session (runs 6 h or more apart are two); without dates, runs.
  std::vector<double> when(t.x.begin(), t.x.begin() + static_cast<std::ptrdiff_t>(n));
  std::sort(when.begin(), when.end());
  std::size_t sessions = 1;
  for (std::size_t i = 1; i < when.size(); ++i) sessions += t.x_unit == "day" ? when[i] - when[i - 1] >= 0.25 : 1;
  const std::string sessions_text = t.x_unit == "day" ? fmt::format("{} session{}", sessions, sessions == 1 ? "" : "s")
                                                       : fmt::format("{} runs", n);
  const std::string over = t.x_unit == "day" ? fmt::format("over {:.3g} days ({} runs, {})", span, n, sessions_text)
                                             : fmt::format("over {} runs", n);
  // A step between two sessions: each side's runs agree on a level (within the scatter a motor has
  // from run to run), the two levels far apart, and the two levels fit far better than the line.
  if (const auto st = find_step(t, w, n, chi2, rules)) {
    t.stepped = true;
    t.drifting = false;
    t.step_x = st->x;
    t.level_before = st->before;
    t.level_after = st->after;
    const double rel = st->after / st->before - 1.0;
    t.words = fmt::format("{} stepped {} {} between {} and {} ({:.3g} to {:.3g} {}; the runs on either side agree): a "
                          "change made then (a repair, a part replaced, another motor), not a drift",
                          what, rel >= 0 ? "up" : "down", percent(std::abs(rel)), x_words(t.x_unit, st->last_before, x0_unix),
                          x_words(t.x_unit, st->first_after, x0_unix), st->before, st->after, t.unit);
    return t;
  }
  // A line that leaves the runs far beyond their errors (a step, a stray run) is no evidence of
  // steadiness: "steady" only when the runs agree with the line.
  const bool line_misses = birge > rules.disagree_scatter;
  std::string verdict = t.drifting ? "drifting" : significant ? "a small but clear change" : "steady within its uncertainty";
  // Runs far apart that line up in time are a drift, not runs of another motor: friction that
  // rises steadily is wear; one that falls steadily, running in (or a lubricant spreading).
  if (t.drifting && !line_misses)
    verdict += t.change >= 0 ? fmt::format(": friction rising steadily over {}: wear (bearings, brushes, alignment)",
                                           sessions_text)
                             : fmt::format(": friction falling steadily over {}: running in, or lubricant spreading",
                                           sessions_text);
  else if (disagree)
    verdict = t.drifting || significant ? verdict + "; " + disagreement : "not steady: " + disagreement;
  else if (line_misses && !t.drifting && !significant)
    verdict = "not steady: the runs scatter far beyond their errors about any straight line";
  t.words = fmt::format("{} {} {} ± {} {}: {}", what, t.change >= 0 ? "rose" : "fell", percent(std::abs(t.relative_change)),
                        percent(t.relative_change_stderr), over, verdict);
  return t;
}

void summarize_session(SessionReport& report) {
  // By bench id, then file (time) order, then run number.
  std::stable_sort(report.runs.begin(), report.runs.end(), [](const ReportRun& a, const ReportRun& b) {
    if (a.bench != b.bench) return a.bench < b.bench;
    if (a.file_index != b.file_index) return a.file_index < b.file_index;
    return a.fit.run.number < b.fit.run.number;
  });
  // Within a bench whose every run has a wall-clock time, that time decides.
  for (auto first = report.runs.begin(); first != report.runs.end();) {
    auto last = std::find_if(first, report.runs.end(), [&](const ReportRun& r) { return r.bench != first->bench; });
    if (std::all_of(first, last, [](const ReportRun& r) { return r.cut_unix_s.has_value(); }))
      std::stable_sort(first, last, [](const ReportRun& a, const ReportRun& b) { return *a.cut_unix_s < *b.cut_unix_s; });
    first = last;
  }
  report.benches.clear();
  for (std::size_t i = 0; i < report.runs.size(); ++i) {
    ReportRun& r = report.runs[i];
    if (report.benches.empty() || report.benches.back().bench != r.bench) {
      report.benches.emplace_back();
      report.benches.back().bench = r.bench;
    }
    BenchSummary& b = report.benches.back();
    b.runs.push_back(i);
    r.order = static_cast<int>(b.runs.size());
    if (static_cast<int>(r.health.level) > static_cast<int>(b.worst)) b.worst = r.health.level;
    if (r.health.has_reference) {
      b.has_reference = true;
      b.reference_file = r.health_config;
    }
  }
  for (BenchSummary& b : report.benches) {
    bool wall_clock = true;
    for (std::size_t i : b.runs) wall_clock = wall_clock && report.runs[i].cut_unix_s.has_value();
    double t0 = 0;
    if (wall_clock && !b.runs.empty()) t0 = *report.runs[b.runs.front()].cut_unix_s;
    std::vector<double> x, cv, cv_se, cc, cc_se;
    for (std::size_t i : b.runs) {
      const ReportRun& r = report.runs[i];
      const auto f = combined_friction(r.fit);
      if (!f) continue;
      x.push_back(wall_clock ? (*r.cut_unix_s - t0) / 86400.0 : static_cast<double>(r.order));
      cv.push_back(f->c_viscous), cv_se.push_back(f->c_viscous_stderr);
      cc.push_back(f->c_coulomb), cc_se.push_back(f->c_coulomb_stderr);
    }
    // Runs minutes apart on one day say nothing per day: fall back to run order then.
    const std::string x_unit =
        wall_clock && !x.empty() && *std::max_element(x.begin(), x.end()) >= 1.0 ? "day" : "run";
    if (x_unit == "run" && wall_clock) {
      x.clear();
      for (std::size_t i : b.runs)
        if (combined_friction(report.runs[i].fit)) x.push_back(static_cast<double>(report.runs[i].order));
    }
    b.viscous = coefficient_trend("c3", "N*m*s/rad", x_unit, x, cv, cv_se, {}, x_unit == "day" ? t0 : 0);
    b.coulomb = coefficient_trend("c4", "N*m", x_unit, x, cc, cc_se, {}, x_unit == "day" ? t0 : 0);
  }
}

bool SessionReport::usable() const {
  for (const auto& f : files)
    if (!f.failures.empty()) return false;
  return true;
}

}  // namespace spindown
