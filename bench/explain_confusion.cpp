// The discrepancy workflow's study: generated runs with a hidden effect (explain_study.hpp),
// per family N runs (default 100), each read back through find_runs and explained from its
// family's base model. Prints the confusion matrix (effect hidden × effect named), the final
// RMSE against a fit of the true structure, and the runs that went wrong.
//   explain_confusion [N] [--verbose]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fmt/format.h>
#include <map>
#include <string>
#include <vector>

#include "explain_study.hpp"
#include "spindown/effect_fit.hpp"
#include "spindown/explain.hpp"
#include "spindown/runs.hpp"

using namespace spindown;

int main(int argc, char** argv) {
  int per_family = 100;
  bool verbose = false;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--verbose") == 0)
      verbose = true;
    else
      per_family = std::max(1, std::atoi(argv[i]));
  }
  const auto& fams = study::families();
  std::vector<std::string> columns = fams;
  columns.push_back("other");
  columns.push_back("no run");
  std::map<std::string, std::map<std::string, int>> confusion;
  std::map<std::string, std::vector<double>> rmse_ratio;
  std::vector<double> millis;
  std::vector<std::string> misses;
  for (const auto& family : fams) {
    for (int k = 0; k < per_family; ++k) {
      const study::GeneratedRun g = study::generate(family, static_cast<std::uint64_t>(k));
      const Segmentation seg = find_runs(g.recording);
      if (seg.runs.empty()) {
        ++confusion[family]["no run"];
        misses.push_back(fmt::format("{} seed {}: no run found", family, k));
        continue;
      }
      ExplainOptions opt;
      opt.bench = g.spec.bench;
      std::string why;
      opt.base = parse_effect_list(g.base, &why);
      const auto t0 = std::chrono::steady_clock::now();
      const ExplainResult r = explain_run(g.recording, seg.runs.front(), opt);
      millis.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      std::string named;
      for (const auto& s : r.steps) named += (named.empty() ? "" : "+") + s.added;
      if (named.empty()) named = "none";
      const std::string column =
          std::find(fams.begin(), fams.end(), named) != fams.end() ? named : std::string("other");
      ++confusion[family][column];
      // The final RMSE against a fit of the true structure on the same samples.
      std::string truth;
      for (const auto& t : g.truth) truth += (truth.empty() ? "" : ",") + t;
      EffectFitData d;
      d.tau = r.tau;
      d.y = r.y;
      const Run& run = seg.runs.front();
      d.moving = std::min((run.stopped ? run.stop_index : run.end_index) - run.cut_index, r.tau.size());
      d.k = opt.bench.kb_v_s_per_rad;
      d.inertia_kg_m2 = opt.bench.inertia_kg_m2;
      const EffectFit truth_fit = fit_effects(parse_effect_list(truth, &why), d);
      const double ratio = r.rmse_final() / truth_fit.rmse;
      if (named == family) rmse_ratio[family].push_back(ratio);
      if (named != family || verbose)
        misses.push_back(fmt::format(
            "{} seed {}: named {} | base {} rmse {:.4g} -> {:.4g} (truth fit {:.4g}, ratio {:.3f}) | period {:.0f} ms "
            "noise {:.4f} ripple {:.3f} lead {} | {}",
            family, k, named, g.base, r.rmse_base(), r.rmse_final(), truth_fit.rmse, ratio, 1000 * g.spec.period_s,
            g.spec.noise_v, g.spec.ripple, static_cast<int>(g.spec.lead_in), r.conclusion));
    }
  }
  fmt::print("Confusion matrix over {} generated runs per family (rows: effect hidden from the base model; "
             "columns: effect the workflow named)\n\n",
             per_family);
  fmt::print("{:<15}", "hidden \\ named");
  for (const auto& c : columns) fmt::print("{:>14}", c);
  fmt::print("\n");
  int right = 0, total = 0;
  for (const auto& family : fams) {
    fmt::print("{:<15}", family);
    for (const auto& c : columns) {
      const int v = confusion[family][c];
      fmt::print("{:>14}", v);
      total += v;
      if (c == family) right += v;
    }
    fmt::print("\n");
  }
  fmt::print("\ncorrect: {}/{} ({:.1f}%)\n", right, total, 100.0 * right / std::max(total, 1));
  fmt::print("\nfinal RMSE / RMSE of a fit of the true structure, when named right (median, max):\n");
  for (const auto& family : fams) {
    auto v = rmse_ratio[family];
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    fmt::print("  {:<14} {:.4f}  {:.4f}\n", family, v[v.size() / 2], v.back());
  }
  std::sort(millis.begin(), millis.end());
  if (!millis.empty())
    fmt::print("\nexplain time per run: median {:.1f} ms, max {:.1f} ms\n", millis[millis.size() / 2], millis.back());
  if (!misses.empty()) {
    fmt::print("\n{}:\n", verbose ? "runs" : "runs named wrong");
    for (const auto& m : misses) fmt::print("  {}\n", m);
  }
  return 0;
}
