#include "spindown/health_baseline.hpp"

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
    m.stderr_ = internal * std::max(1.0, birge);
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
  BaselineRun r;
  r.source = std::move(source);
  r.c_viscous = cv->value;
  r.c_viscous_stderr = cv->std_error;
  r.c_coulomb = cc->value;
  r.c_coulomb_stderr = cc->std_error;
  r.inertia_kg_m2 = fit.bench.inertia_kg_m2;
  return r;
}

std::optional<HealthBaseline> make_baseline(std::span<const BaselineRun> runs, std::string date, std::string source,
                                            std::string* why) {
  if (runs.empty()) return fail(why, "no good run (a combined fit that converged) to make a baseline from"), std::nullopt;
  std::vector<double> cv, cv_se, cc, cc_se;
  double J = 0;
  for (const auto& r : runs) {
    cv.push_back(r.c_viscous);
    cv_se.push_back(r.c_viscous_stderr);
    cc.push_back(r.c_coulomb);
    cc_se.push_back(r.c_coulomb_stderr);
    J += r.inertia_kg_m2;
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
  b.source = std::move(source);
  if (!(b.c_coulomb >= 0 && b.c_viscous >= 0))
    return fail(why, fmt::format("mean coefficients are negative (c_v {:.4g}, c_c {:.4g}): not a usable baseline",
                                 b.c_viscous, b.c_coulomb)),
           std::nullopt;
  return b;
}

std::string baseline_toml_section(const HealthBaseline& b) {
  std::string out = "[baseline]\n";
  out += fmt::format("# written by `spindown baseline`: combined-model friction of {} good run{}, weighted mean ± "
                     "standard error; spread = run-to-run standard deviation\n",
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
