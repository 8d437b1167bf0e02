#include "spindown/bench_naming.hpp"
#include "spindown/unicode_nfc.hpp"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>

#include "spindown/file_bytes.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/ascii_lower.hpp"
#include "spindown/csv_fields.hpp"
#include "spindown/text_encoding.hpp"
#include "spindown/text_support.hpp"
#include "spindown/trim.hpp"

namespace spindown {

namespace {

char header_delimiter(std::string_view header) {
  for (const char d : {'\t', ';', ','})
    if (header.find(d) != std::string_view::npos) return d;
  return ',';
}

}  // namespace

std::string file_stem(const std::string& path) {
  std::string name = std::filesystem::path(path).filename().string();
  const auto dot = name.find_last_of('.');
  if (dot != std::string::npos && dot > 0) name.resize(dot);
  return name.empty() ? path : name;
}

ClassRoster load_class_roster(const std::string& path) {
  std::string why;
  std::optional<std::string> bytes = read_file_bytes(path, &why, std::size_t{16} << 20);
  if (!bytes) throw std::runtime_error(why);
  constexpr std::string_view save_as = "save it from the spreadsheet as CSV UTF-8 (File > Save As > \"CSV UTF-8\")";
  if (const auto office = office_document(*bytes))
    throw std::runtime_error(fmt::format("{}: a roster must be text: {}", path, *office));
  // What a spreadsheet writes: UTF-8 with a byte-order mark, UTF-16 ("Unicode text"), Windows-1252
  // (a German Excel's "CSV (Trennzeichen-getrennt)").
  const EncodingGuess encoding = guess_text_encoding(*bytes);
  const bool wide = encoding.encoding == TextEncoding::utf16le || encoding.encoding == TextEncoding::utf16be;
  std::size_t control = 0, looked_at = 0;
  if (!wide && text::looks_binary(*bytes, &control, &looked_at))
    throw std::runtime_error(fmt::format("{}: not a roster: binary data ({} of the first {} bytes are control "
                                         "characters or NUL); {}",
                                         path, control, looked_at, save_as));
  if (encoding.encoding == TextEncoding::mixed)
    throw std::runtime_error(fmt::format("{}: {} byte{} neither UTF-8 nor of one other encoding, so names "
                                         "cannot be read right; {}",
                                         path, encoding.not_utf8, encoding.not_utf8 == 1 ? " is" : "s are", save_as));
  if (needs_decoding(encoding)) *bytes = decode_text(*bytes, encoding);
  ClassRoster roster;
  roster.path = path;
  char delim = 0;
  std::optional<std::size_t> col_file, col_bench, col_student;
  std::size_t columns = 0;
  CsvFieldSplitter splitter;
  std::vector<std::string_view> views;
  const auto split_row = [&](std::string_view line) {
    splitter.split(line, delim, views);
    return std::vector<std::string>(views.begin(), views.end());
  };
  text::for_each_line(*bytes, [&](std::int64_t number, std::string_view raw) {
    const std::string line(trim(raw));
    if (line.empty() || line.front() == '#') return;
    const auto at = [&](std::string_view what) {
      return std::runtime_error(fmt::format("{}:{}: {}", path, number, what));
    };
    if (columns == 0 && delim == 0 && line.size() == 5 && ascii_lower(line.substr(0, 4)) == "sep=") {
      delim = line[4];  // Excel's hint for the delimiter ("sep=;")
      return;
    }
    if (columns == 0) {  // the header
      if (delim == 0) delim = header_delimiter(line);
      const std::vector<std::string> names = split_row(line);
      if (std::all_of(names.begin(), names.end(), [](const std::string& x) { return x.empty(); })) return;
      columns = names.size();
      for (std::size_t i = 0; i < names.size(); ++i) {
        const std::string n = ascii_lower(names[i]);
        if (n == "file" || n == "filename" || n == "file name" || n == "datei" || n == "dateiname") col_file = i;
        if (n == "bench" || n == "bench_id" || n == "bench id" || n == "platz" || n == "pr\xc3\xbc" "fstand") col_bench = i;
        if (n == "student" || n == "name" || n == "students" || n == "studierende") col_student = i;
      }
      if (!col_file || !col_bench)
        throw at(fmt::format("the header '{}' needs a 'file' and a 'bench' column (e.g. file,bench,student)", line));
      return;
    }
    const std::vector<std::string> f = split_row(line);
    // A spreadsheet's empty rows (";;;;", ",,,"): nothing in them.
    if (std::all_of(f.begin(), f.end(), [](const std::string& x) { return x.empty(); })) return;
    if (f.size() <= *col_bench && f.size() > *col_file && !trim(f[*col_file]).empty())
      throw at(fmt::format("{} field{} where the header has {}: '{}'", f.size(), f.size() == 1 ? "" : "s", columns, line));
    if (f.size() <= *col_file || trim(f[*col_file]).empty()) {  // a points row, a student without a file
      std::string who;
      for (const auto& x : f)
        if (!trim(x).empty()) {
          who = std::string(trim(x));
          break;
        }
      roster.skipped.push_back(fmt::format("{}:{}: no file{}: skipped", path, number,
                                           who.empty() ? std::string() : fmt::format(" ({})", nfc(who))));
      return;
    }
    RosterEntry e{nfc(f[*col_file]), f[*col_bench], nfc(col_student && *col_student < f.size() ? f[*col_student] : ""),
                  static_cast<std::size_t>(number)};
    std::string bad;
    if (!is_valid_bench_id(e.bench, &bad)) throw at(fmt::format("bench '{}': {}", e.bench, bad));
    for (const auto& other : roster.entries)
      if (other.file == e.file && other.bench != e.bench)
        throw at(fmt::format("'{}' is bench '{}' here but bench '{}' on line {}", e.file, e.bench, other.bench,
                             other.line));
    roster.entries.push_back(std::move(e));
  });
  if (columns == 0) throw std::runtime_error(fmt::format("{}: empty: a roster needs a header 'file,bench[,student]'", path));
  if (roster.entries.empty()) throw std::runtime_error(fmt::format("{}: the roster lists no file", path));
  return roster;
}

BenchNaming::BenchNaming(const std::string& roster_path, const std::string& pattern, const std::string& fixed_bench)
    : pattern_text_(pattern), fixed_(fixed_bench) {
  if (!roster_path.empty()) roster_ = load_class_roster(roster_path);
  if (!pattern.empty()) {
    try {
      pattern_.emplace(pattern, std::regex::ECMAScript);
    } catch (const std::regex_error& e) {
      throw std::invalid_argument(fmt::format("--bench-pattern '{}' is not a regular expression: {}", pattern, e.what()));
    }
    if (pattern_->mark_count() < 1)
      throw std::invalid_argument(
          fmt::format("--bench-pattern '{}' has no group: put the bench id in parentheses, e.g. '(bench[0-9]+)'",
                      pattern));
  }
  std::string why;
  if (!fixed_.empty() && !is_valid_bench_id(fixed_, &why))
    throw std::invalid_argument(fmt::format("--bench '{}': {}", fixed_, why));
}

BenchName BenchNaming::name(const std::string& path, const std::string& fallback) const {
  namespace fs = std::filesystem;
  std::vector<std::string> problems;
  bool shared_name = false;
  if (roster_) {
    // Paths and names compared in NFC: a roster typed on Windows and folders unzipped on a Mac
    // (NFD) spell "Jürgen" with different bytes (unicode_nfc.hpp).
    const fs::path given = fs::path(nfc(fs::path(path).lexically_normal().string()));
    const std::string base = given.filename().string();
    const fs::path roster_dir = fs::path(roster_->path).parent_path();
    std::error_code ec;
    const fs::path real = fs::path(nfc(fs::weakly_canonical(fs::path(path), ec).string()));
    const RosterEntry* by_path = nullptr;
    std::vector<const RosterEntry*> by_name;
    for (const auto& e : roster_->entries) {
      const fs::path listed = fs::path(nfc(fs::path(e.file).lexically_normal().string()));
      if (listed == given) by_path = &e;
      if (!by_path && !real.empty()) {
        const fs::path there = fs::path(nfc(fs::weakly_canonical(roster_dir / listed, ec).string()));
        if (!ec && there == real) by_path = &e;
      }
      if (listed.filename().string() == base) by_name.push_back(&e);
      if (by_path) break;
    }
    const RosterEntry* hit = by_path ? by_path : by_name.size() == 1 ? by_name.front() : nullptr;
    if (hit) return {hit->bench, hit->student, fmt::format("roster {}:{}", roster_->path, hit->line), {}};
    // A name the roster gives several students' files (putty.log, log.txt) is no bench's name.
    if (by_name.size() > 1) shared_name = true;
    problems.push_back(by_name.size() > 1
                           ? fmt::format("the roster {} lists several files named '{}' (lines {} and {}): give its "
                                         "folder too",
                                         roster_->path, base, by_name[0]->line, by_name[1]->line)
                           : fmt::format("not in the roster {}", roster_->path));
  }
  if (pattern_) {
    const std::string name = fs::path(path).filename().string();
    std::smatch m;
    if (std::regex_search(name, m, *pattern_) && m[1].matched && m[1].length() > 0) {
      std::string why;
      if (is_valid_bench_id(m[1].str(), &why))
        return {m[1].str(), pattern_->mark_count() >= 2 && m[2].matched ? m[2].str() : "", "--bench-pattern", {}};
      problems.push_back(fmt::format("--bench-pattern took '{}' from the file name, not a bench id: {}", m[1].str(), why));
    } else {
      problems.push_back(fmt::format("its name does not match --bench-pattern '{}'", pattern_text_));
    }
  }
  if (!fixed_.empty()) return {fixed_, "", "--bench", {}};
  std::string problem;
  for (const auto& p : problems) problem += (problem.empty() ? "" : "; ") + p;
  if (shared_name) {  // never a bench made up of a name several students' files share
    problem += "; reported under no bench";
    return {"", "", "", problem};
  }
  if (!problem.empty())
    problem += fallback.empty() ? "" : fmt::format("; reported as bench '{}' (its file name)", fallback);
  return {fallback, "", "", problem};
}

}  // namespace spindown
