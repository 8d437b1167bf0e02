#pragma once
// Shared by the fit report's text (fit_report.cpp), its JSON (fit_json.cpp) and the run table
// (run_table.cpp). Private to the report module.
#include <cstddef>

#include "spindown/fit.hpp"
#include "spindown/recording.hpp"

namespace spindown {

inline const char* severity_name(Diagnostic::Severity s) {
  switch (s) {
    case Diagnostic::Severity::error: return "error";
    case Diagnostic::Severity::warning: return "warning";
    case Diagnostic::Severity::note: return "note";
  }
  return "warning";
}

// The run's best model (fit.best), or nullptr when none was chosen.
inline const ModelFit* best_model(const RunFit& fit) {
  for (const auto& m : fit.models)
    if (model_name(m.kind) == fit.best) return &m;
  return nullptr;
}

// Samples from the cut to the run's end.
inline std::size_t samples_in(const Run& run) {
  return run.end_index > run.cut_index ? run.end_index - run.cut_index : 0;
}

}  // namespace spindown
