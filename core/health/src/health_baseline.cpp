#include "spindown/health_baseline.hpp"

#include <algorithm>

#include <cmath>
#include <fmt/format.h>
#include <regex>
#include <sstream>
#include <toml++/toml.h>

namespace spindown {

namespace {

bool fail(std::string* why, std::string text) {
  if (why) *why = std::move(text);
  return false;
}

struct Mean {
  double value = 0, stderr_ = 0, spread = 0;
};

// Inverse-variance weighted mean (plain mean when any run has no usable error).
Mean weighted_mean(const std::vector<double>& x, const std::vector<double>& se) {
  const std::size_t n = x.size();
  bool weighted = true;
  for (double s : se) weighted = weighted && std::isfinite(s) && s > 0;
  double sw = 0, swx = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weighted ? 1.0 / (se[i] * se[i]) : 1.0;
    sw += w;
    swx += w * x[i];
  }
  Mean m;
  m.value = swx / sw;
  double ss = 0, chi2 = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ss += (x[i] - m.value) * (x[i] - m.value);
    if (weighted) chi2 += (x[i] - m.value) * (x[i] - m.value) / (se[i] * se[i]);
  }
  m.spread = n > 1 ? std::sqrt(ss / double(n - 1)) : 0.0;
  if (weighted) {
    const double internal = 1.0 / std::sqrt(sw);
    const double birge = n > 1 ? std::sqrt(chi2 / double(n - 1)) : 1.0;
    m.stderr_ = std::max(internal * std::max(1.0, birge), n > 1 ? m.spread / std::sqrt(double(n)) : 0.0);
  } else {
    m.stderr_ = n > 1 ? m.spread / std::sqrt(double(n)) : (se.empty() ? 0.0 : std::fabs(se[0]));
    if (!std::isfinite(m.stderr_)) m.stderr_ = 0;
  }
  return m;
}

std::string toml_number(double x) {
  std::string s = fmt::format("{:.9g}", x);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";  // stays a float in TOML
  return s;
}

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      out += fmt::format("\\u{:04x}", static_cast<unsigned char>(c));
    } else {
      out += c;
    }
  }
  return out + '"';
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool blank_or_comment(const std::string& line) {
  const auto p = line.find_first_not_of(" \t\r");
  return p == std::string::npos || line[p] == '#';
}

}  // namespace

std::optional<BaselineRun> baseline_run(const RunFit& fit, std::string source, std::string* why) {
  const ModelFit* m = fit.model(ModelKind::combined);
  if (!m) return fail(why, "no combined fit"), std::nullopt;
  if (!m->converged)
    return fail(why, fmt::format("combined fit did not converge{}", m->message.empty() ? "" : ": " + m->message)),
           std::nullopt;
  const Parameter* cv = m->param("c3");
  const Parameter* cc = m->param("c4");
  if (!cv || !cc || !std::isfinite(cv->value) || !std::isfinite(cc->value))
    return fail(why, "combined fit has no finite c3/c4"), std::nullopt;
  if (fit.run.partial())
    return fail(why, "the cut was not recorded (the coast is partial): its friction is not a whole coast's"),
           std::nullopt;
  if (!fit.run.stopped)
    return fail(why, fmt::format("the run never stopped (its window ends: {}): its friction is not a whole coast's",
                                 end_name(fit.run.end))),
           std::nullopt;
  BaselineRun r;
  r.source = std::move(source);
  r.c_viscous = cv->value;
  r.c_viscous_stderr = cv->std_error;
  r.c_coulomb = cc->value;
  r.c_coulomb_stderr = cc->std_error;
  r.inertia_kg_m2 = fit.bench.inertia_kg_m2;
  r.omega0 = std::isfinite(m->omega0) && m->omega0 > 0 ? m->omega0 : 0;
  return r;
}

namespace {

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// How far each run's coefficient lies from the runs' median, in standard errors that count the
// run's own error and the runs' natural scatter (robust: 1.4826·MAD, at least a fraction of the
// median).
std::vector<double> robust_z(const std::vector<double>& x, const std::vector<double>& se) {
  const double med = median_of(x);
  std::vector<double> dev;
  for (double v : x) dev.push_back(std::fabs(v - med));
  const double scatter = std::max(1.4826 * median_of(dev), baseline_natural_scatter * std::fabs(med));
  std::vector<double> z;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double s = std::hypot(std::isfinite(se[i]) ? se[i] : 0.0, scatter);
    z.push_back(s > 0 ? (x[i] - med) / s : 0.0);
  }
  return z;
}

std::string times_median(double x, double med) {
  return med > 0 ? fmt::format("{:.2g}× the others' median", x / med) : fmt::format("{:.3g}", x);
}

}  // namespace

std::optional<HealthBaseline> make_baseline(std::span<const BaselineRun> all_runs, std::string date,
                                            std::string source, std::string* why,
                                            std::vector<SetAsideRun>* set_aside) {
  if (all_runs.empty())
    return fail(why, "no good run (a combined fit that converged) to make a baseline from"), std::nullopt;
  std::vector<BaselineRun> runs(all_runs.begin(), all_runs.end());
  {
    std::vector<double> cv, cv_se, cc, cc_se;
    for (const auto& r : runs) {
      cv.push_back(r.c_viscous);
      cv_se.push_back(r.c_viscous_stderr);
      cc.push_back(r.c_coulomb);
      cc_se.push_back(r.c_coulomb_stderr);
    }
    if (runs.size() == 2) {
      // Two runs: a median cannot tell which one is off; they must agree with each other.
      const auto disagree = [&](const std::vector<double>& x, const std::vector<double>& se) {
        const double scatter = baseline_natural_scatter * 0.5 * std::fabs(x[0] + x[1]);
        const double s = std::sqrt(se[0] * se[0] + se[1] * se[1] + 2 * scatter * scatter);
        return s > 0 ? std::fabs(x[0] - x[1]) / s : 0.0;
      };
      const double zc = disagree(cc, cc_se), zv = disagree(cv, cv_se);
      if (std::max(zc, zv) > baseline_outlier_sigma)
        return fail(why, fmt::format("the 2 runs disagree ({} differs by {:.0f} standard errors, counting {:.0f} % "
                                     "run-to-run scatter): which one is the motor's normal cannot be told — "
                                     "record a third good run",
                                     zc >= zv ? "dry friction" : "viscous friction", std::max(zc, zv),
                                     100 * baseline_natural_scatter)),
               std::nullopt;
    } else if (runs.size() >= 3) {
      const std::vector<double> zv = robust_z(cv, cv_se), zc = robust_z(cc, cc_se);
      const double med_v = median_of(cv), med_c = median_of(cc);
      std::vector<BaselineRun> kept;
      for (std::size_t i = 0; i < runs.size(); ++i) {
        const bool off_c = std::fabs(zc[i]) > baseline_outlier_sigma, off_v = std::fabs(zv[i]) > baseline_outlier_sigma;
        if (!off_c && !off_v) {
          kept.push_back(runs[i]);
          continue;
        }
        const bool by_c = std::fabs(zc[i]) >= std::fabs(zv[i]);
        const std::string what =
            by_c ? fmt::format("dry friction {} ({:.0f} standard errors)", times_median(cc[i], med_c), std::fabs(zc[i]))
                 : fmt::format("viscous friction {} ({:.0f} standard errors)", times_median(cv[i], med_v),
                               std::fabs(zv[i]));
        if (set_aside)
          set_aside->push_back({runs[i].source, what + ": worn, another motor, or a bad run — not this motor's normal"});
      }
      if (kept.size() * 2 < runs.size())
        return fail(why, fmt::format("{} of {} runs disagree with the others' median: no common normal to make a "
                                     "baseline of",
                                     runs.size() - kept.size(), runs.size())),
               std::nullopt;
      runs = std::move(kept);
    }
  }
  std::vector<double> cv, cv_se, cc, cc_se;
  double J = 0, w0 = 0, w0_sq = 0;
  bool every_w0 = true;
  for (const auto& r : runs) {
    cv.push_back(r.c_viscous);
    cv_se.push_back(r.c_viscous_stderr);
    cc.push_back(r.c_coulomb);
    cc_se.push_back(r.c_coulomb_stderr);
    J += r.inertia_kg_m2;
    w0 += r.omega0;
    w0_sq += r.omega0 * r.omega0;
    every_w0 = every_w0 && r.omega0 > 0;
  }
  const Mean v = weighted_mean(cv, cv_se);
  const Mean c = weighted_mean(cc, cc_se);
  HealthBaseline b;
  b.c_viscous = v.value;
  b.c_viscous_stderr = v.stderr_;
  b.c_viscous_spread = v.spread;
  b.c_coulomb = c.value;
  b.c_coulomb_stderr = c.stderr_;
  b.c_coulomb_spread = c.spread;
  b.runs = static_cast<int>(runs.size());
  b.date = std::move(date);
  b.inertia_kg_m2 = J / double(runs.size());
  if (every_w0) {
    const double n = double(runs.size());
    b.omega0 = w0 / n;
    b.omega0_spread = n > 1 ? std::sqrt(std::max(0.0, (w0_sq - n * b.omega0 * b.omega0) / (n - 1))) : 0;
  }
  b.source = std::move(source);
  if (!(b.c_coulomb >= 0 && b.c_viscous >= 0))
    return fail(why, fmt::format("mean coefficients are negative (c3 {:.4g}, c4 {:.4g}): not a usable baseline",
                                 b.c_viscous, b.c_coulomb)),
           std::nullopt;
  return b;
}

std::string baseline_toml_section(const HealthBaseline& b) {
  std::string out = "[baseline]\n";
  out += fmt::format("# written by `spindown baseline`: combined-model friction of {} good run{} (c_viscous = fit's "
                     "c3, c_coulomb = fit's c4), weighted mean ± standard error; spread = run-to-run standard "
                     "deviation\n",
                     b.runs, b.runs == 1 ? "" : "s");
  out += fmt::format("c_viscous_n_m_s = {}\n", toml_number(b.c_viscous));
  out += fmt::format("c_viscous_stderr = {}\n", toml_number(b.c_viscous_stderr));
  out += fmt::format("c_viscous_spread = {}\n", toml_number(b.c_viscous_spread));
  out += fmt::format("c_coulomb_n_m = {}\n", toml_number(b.c_coulomb));
  out += fmt::format("c_coulomb_stderr = {}\n", toml_number(b.c_coulomb_stderr));
  out += fmt::format("c_coulomb_spread = {}\n", toml_number(b.c_coulomb_spread));
  out += fmt::format("runs = {}\n", b.runs);
  out += fmt::format("date = {}\n", toml_string(b.date));
  if (b.inertia_kg_m2 > 0) out += fmt::format("inertia_kg_m2 = {}\n", toml_number(b.inertia_kg_m2));
  if (b.omega0 > 0) {
    out += "# mean speed at the cut as read (the lab's supply gives about the same every run), and its spread\n";
    out += fmt::format("omega0_rad_s = {}\n", toml_number(b.omega0));
    out += fmt::format("omega0_spread = {}\n", toml_number(b.omega0_spread));
  }
  if (!b.source.empty()) out += fmt::format("source = {}\n", toml_string(b.source));
  return out;
}

std::optional<std::string> with_baseline_section(const std::string& text, const HealthBaseline& b, std::string* why) {
  toml::table before;
  try {
    before = toml::parse(text);
  } catch (const toml::parse_error& e) {
    return fail(why, fmt::format("line {}: {}", e.source().begin.line, e.description())), std::nullopt;
  }
  if (const auto* n = before.get("baseline"); n && !n->is_table())
    return fail(why, "'baseline' is not a table"), std::nullopt;

  static const std::regex header(R"(^\s*\[\s*baseline\s*\]\s*(#.*)?\r?$)");
  static const std::regex any_header(R"(^\s*\[)");
  const auto lines = lines_of(text);
  std::size_t start = lines.size(), end = lines.size();
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (std::regex_search(lines[i], header)) {
      start = i;
      break;
    }
  std::string out;
  const std::string section = baseline_toml_section(b);
  if (start == lines.size()) {
    if (before.contains("baseline"))
      return fail(why, "the baseline is not written as a [baseline] table (dotted keys or an inline table)"),
             std::nullopt;
    out = text;
    if (!out.empty() && out.back() != '\n') out += '\n';
    out += '\n' + section;
  } else {
    for (std::size_t i = start + 1; i < lines.size(); ++i)
      if (std::regex_search(lines[i], any_header)) {
        end = i;
        break;
      }
    // Comments just above the next header belong to that section: keep them.
    std::size_t cut = end;
    while (cut > start + 1 && blank_or_comment(lines[cut - 1])) --cut;
    for (std::size_t i = 0; i < start; ++i) out += lines[i] + '\n';
    out += section;
    for (std::size_t i = cut; i < lines.size(); ++i) out += lines[i] + '\n';
  }
  // Check: the new text parses, holds this baseline, and every other key is unchanged.
  toml::table after;
  try {
    after = toml::parse(out);
  } catch (const toml::parse_error& e) {
    return fail(why, fmt::format("the updated file would not parse (line {}: {})", e.source().begin.line,
                                 e.description())),
           std::nullopt;
  }
  const auto* nb = after.get("baseline");
  if (!nb || !nb->is_table() || nb->as_table()->get("c_coulomb_n_m") == nullptr)
    return fail(why, "the updated file would not hold the new [baseline]"), std::nullopt;
  toml::table rest_before = before, rest_after = after;
  rest_before.erase("baseline");
  rest_after.erase("baseline");
  if (rest_before != rest_after)
    return fail(why, "replacing [baseline] in place would change other keys (a subtable of [baseline]?)"),
           std::nullopt;
  return out;
}

}  // namespace spindown
