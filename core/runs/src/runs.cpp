#include "spindown/runs.hpp"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>

#include "spindown/run_detector.hpp"

namespace spindown {

bool RunOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string msg) {
    if (why) *why = std::move(msg);
    return false;
  };
  auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  if (!positive(stop_hold_s)) return fail(fmt::format("stop_hold_s must be > 0 (got {})", stop_hold_s));
  if (!(std::isfinite(min_coast_s) && min_coast_s >= 0))
    return fail(fmt::format("min_coast_s must be >= 0 (got {})", min_coast_s));
  if (!(max_coast_s > 0) || max_coast_s <= min_coast_s)  // +inf: no cap (offline)
    return fail(fmt::format("max_coast_s must be > min_coast_s (got {} and {})", max_coast_s, min_coast_s));
  if (!(std::isfinite(tail_s) && tail_s >= 0)) return fail(fmt::format("tail_s must be >= 0 (got {})", tail_s));
  if (max_buffer < 64) return fail(fmt::format("max_buffer must be at least 64 samples (got {})", max_buffer));
  return true;
}

const char* end_name(Run::End e) {
  switch (e) {
    case Run::End::stopped: return "stopped";
    case Run::End::signal_lost: return "signal lost";
    case Run::End::gap: return "gap";
    case Run::End::end_of_data: return "end of data";
    case Run::End::cap: return "cap";
    case Run::End::power_back: return "power back";
    case Run::End::clock_restart: return "clock restart";
    case Run::End::asymptotic: return "asymptotic";
    case Run::End::silent: return "silent";
    case Run::End::new_source: return "new source";
  }
  return "?";
}

Run::End end_from_name(std::string_view name) {
  for (Run::End e : {Run::End::stopped, Run::End::signal_lost, Run::End::gap, Run::End::end_of_data, Run::End::cap,
                     Run::End::power_back, Run::End::clock_restart, Run::End::asymptotic, Run::End::silent,
                     Run::End::new_source})
    if (name == end_name(e)) return e;
  return Run::End::end_of_data;
}

Segmentation find_runs(const Recording& rec, const RunOptions& opt) {
  Segmentation seg;
  auto diag = [&](Diagnostic::Severity sev, std::string msg) {
    seg.diagnostics.push_back({sev, rec.source, 0, std::move(msg)});
  };
  std::string why;
  if (!opt.is_valid(&why)) {
    diag(Diagnostic::Severity::error, "run options: " + why);
    return seg;
  }
  if (rec.t_s.size() != rec.value.size()) {
    diag(Diagnostic::Severity::error, fmt::format("{} times but {} values: recording not segmented", rec.t_s.size(),
                                                  rec.value.size()));
    return seg;
  }
  if (rec.empty()) {
    diag(Diagnostic::Severity::warning, "no samples: no runs");
    return seg;
  }

  std::vector<std::size_t> restarts = rec.clock_restarts;
  std::sort(restarts.begin(), restarts.end());
  auto next_restart = restarts.begin();

  RunDetector det(opt, rec.source);
  det.set_quantity(rec.quantity);
  auto collect = [&] {
    for (RunEvent& e : det.take_events()) {
      if (e.has_diagnostic) seg.diagnostics.push_back(e.diagnostic);
      if (e.kind == RunEvent::Kind::complete) seg.runs.push_back(std::move(e.run));  // indices mapped below
    }
  };
  // The samples between declared restarts in one go; events keep their order in the detector.
  for (std::size_t i = 0; i < rec.size();) {
    while (next_restart != restarts.end() && *next_restart <= i) {
      if (*next_restart == i && i > 0) det.clock_restart();
      ++next_restart;
    }
    const std::size_t end = next_restart != restarts.end() ? std::min(*next_restart, rec.size()) : rec.size();
    det.push_many(rec.t_s.data() + i, rec.value.data() + i, end - i);
    collect();
    i = end;
  }
  det.finish();
  collect();
  // The detector numbers only finite samples (it skips the others): when it saw fewer than all,
  // map its indices back to the recording's. Known only now, so the runs wait for it.
  if (det.samples_seen() != rec.size()) {
    std::vector<std::size_t> index_of;
    for (std::size_t i = 0; i < rec.size(); ++i)
      if (std::isfinite(rec.t_s[i]) && std::isfinite(rec.value[i])) index_of.push_back(i);
    const auto map = [&](std::size_t k) { return k < index_of.size() ? index_of[k] : rec.size(); };
    for (Run& r : seg.runs) {
      r.cut_index = map(r.cut_index);
      r.stop_index = map(r.stop_index);
      r.end_index = map(r.end_index);
      for (std::size_t& k : r.outliers) k = map(k);
    }
  }
  if (seg.runs.empty())
    diag(Diagnostic::Severity::warning,
         fmt::format("no spin-down found in {} samples (no smooth decline after a cut)", rec.size()));
  return seg;
}

}  // namespace spindown
