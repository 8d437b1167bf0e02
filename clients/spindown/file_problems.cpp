#include "file_problems.hpp"

#include <algorithm>

#include "spindown/fit_report.hpp"

namespace spindown::cli {

void report_file_problems(std::ostream& err, const std::string& file, const std::vector<Diagnostic>& diagnostics,
                          const std::vector<std::string>& failures, bool verbose, std::size_t max_shown) {
  // An error that made the file unusable is said once, by its "not used" line.
  auto is_a_failure = [&](const Diagnostic& d) {
    return d.severity == Diagnostic::Severity::error &&
           std::any_of(failures.begin(), failures.end(), [&](const std::string& why) {
             return why.size() >= d.message.size() && why.ends_with(d.message);
           });
  };
  std::vector<Diagnostic> shown;
  for (const auto& d : diagnostics)
    if ((verbose || d.severity != Diagnostic::Severity::note) && !is_a_failure(d)) shown.push_back(d);
  for (const auto& line : summarize_diagnostics(shown, max_shown)) err << line << '\n';
  for (const auto& why : failures) err << file << ": error: not used: " << why << '\n';
  err.flush();
}

}  // namespace spindown::cli
