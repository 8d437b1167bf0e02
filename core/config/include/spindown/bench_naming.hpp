#pragma once
// Which bench (and which student) a text recording is from, for a class's files: a text file
// names no bench, so the instructor says it, by a roster file (one row per file) or by a
// pattern in the file names. LCM logs name their own benches and are never renamed.
//
// Roster: delimited text (comma, semicolon or tab, as a spreadsheet saves it) with a header
// naming the columns `file` and `bench`, optionally `student`; other columns are ignored, `#`
// starts a comment line. A row's file is matched against a recording's path as given, then
// relative to the roster's folder, then by its file name alone (when that is unique in the roster).
//
// Pattern: an ECMAScript regular expression searched in the file's name (not its folders); its
// first group is the bench id, a second group the student, e.g. `(bench[0-9]+)_([a-z]+)` for
// bench3_alice.txt.
#include <cstddef>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <vector>

namespace spindown {

struct RosterEntry {
  std::string file;     // as the roster writes it
  std::string bench;
  std::string student;  // "" when the roster has no student column
  std::size_t line = 0;
};

struct ClassRoster {
  std::string path;
  std::vector<RosterEntry> entries;
  // Rows without a file, skipped and named ("roster.csv:3: no file (Points Possible): skipped"): a
  // learning-management system's export holds a points row and students who handed nothing in.
  std::vector<std::string> skipped;
};

// Reads a roster. Throws std::runtime_error naming the file and line (a missing column, a bad
// bench id, a file listed twice with different benches).
ClassRoster load_class_roster(const std::string& path);

struct BenchName {
  std::string bench;    // "" when nothing names it
  std::string student;  // "" when not known
  std::string from;     // "roster FILE:LINE", "--bench-pattern", "--bench"
  std::string problem;  // why the rule that was asked for did not name this file ("" when it did)
};

class BenchNaming {
 public:
  BenchNaming() = default;
  // Throws std::runtime_error for a roster that cannot be read (naming the file and line) and
  // std::invalid_argument for a pattern that does not compile or has no group, or a bad fixed id
  // (naming the option).
  BenchNaming(const std::string& roster_path, const std::string& pattern, const std::string& fixed_bench = {});

  bool active() const { return roster_.has_value() || pattern_.has_value() || !fixed_.empty(); }
  // The roster's rows skipped for having no file (said once, by whoever reads the roster).
  const std::vector<std::string>& roster_skipped() const {
    static const std::vector<std::string> none;
    return roster_ ? roster_->skipped : none;
  }
  // The roster first, then the pattern, then the fixed bench. A file neither names gets
  // fallback (the caller's: "" or the file's name) and a problem.
  BenchName name(const std::string& path, const std::string& fallback = {}) const;

 private:
  std::optional<ClassRoster> roster_;
  std::optional<std::regex> pattern_;
  std::string pattern_text_;
  std::string fixed_;
};

// A file's name without its folders and its last extension ("runs/bench3.txt" -> "bench3").
std::string file_stem(const std::string& path);

}  // namespace spindown
