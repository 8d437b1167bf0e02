#pragma once
// A file's problems on stderr, said the same way by every subcommand that reads files.
#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "spindown/recording.hpp"

namespace spindown::cli {

// Warnings and errors always, notes only when verbose, each naming the file (and line); at most
// max_shown of them before a count (0: all). Then each failure once, as "FILE: error: not used:
// WHY": an error diagnostic that a failure already says is not said a second time.
void report_file_problems(std::ostream& err, const std::string& file, const std::vector<Diagnostic>& diagnostics,
                          const std::vector<std::string>& failures, bool verbose, std::size_t max_shown);

}  // namespace spindown::cli
