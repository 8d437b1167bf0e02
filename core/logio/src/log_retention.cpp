#include "spindown/log_retention.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <dirent.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

namespace spindown {

bool LogRetentionOptions::is_valid(std::string* why) const {
  auto fail = [&](std::string reason) {
    if (why) *why = std::move(reason);
    return false;
  };
  if (keep_files < 0) return fail(fmt::format("keep files {} must be >= 0 (0 = no limit)", keep_files));
  if (keep_files == 1) return fail("keep files 1 would keep only the file being written: use 2 or more (0 = no limit)");
  if (!std::isfinite(keep_mb) || keep_mb < 0) return fail(fmt::format("keep MB {} must be >= 0 (0 = no limit)", keep_mb));
  return true;
}

namespace {

// Oldest = earliest modification time, then name.
void sort_oldest_first(std::vector<LogFileInfo>& files) {
  std::sort(files.begin(), files.end(), [](const LogFileInfo& a, const LogFileInfo& b) {
    return a.mtime_ns != b.mtime_ns ? a.mtime_ns < b.mtime_ns : a.path < b.path;
  });
}

}  // namespace

std::vector<LogFileInfo> files_to_prune(std::vector<LogFileInfo> files, std::string_view current,
                                        const LogRetentionOptions& o) {
  std::vector<LogFileInfo> out;
  if (!o.enabled()) return out;
  sort_oldest_first(files);
  std::int64_t count = static_cast<std::int64_t>(files.size());
  double bytes = 0;
  for (const auto& f : files) bytes += double(f.bytes);
  const double budget = o.keep_mb * 1e6;
  auto over = [&] { return (o.keep_files > 0 && count > o.keep_files) || (o.keep_mb > 0 && bytes > budget); };
  for (const auto& f : files) {
    if (!over()) break;
    if (f.path == current) continue;
    out.push_back(f);
    --count;
    bytes -= double(f.bytes);
  }
  return out;
}

bool is_own_log_file_name(std::string_view name, std::string_view prefix, std::string_view bench) {
  // PREFIX-YYYY-MM-DD-HHMMSS[-BENCH][.N].lcm
  if (!name.starts_with(prefix) || !name.ends_with(".lcm")) return false;
  name.remove_prefix(prefix.size());
  name.remove_suffix(4);
  static constexpr std::string_view pattern = "-0000-00-00-000000";
  if (name.size() < pattern.size()) return false;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    const bool digit = std::isdigit(static_cast<unsigned char>(name[i])) != 0;
    if (pattern[i] == '0' ? !digit : name[i] != '-') return false;
  }
  name.remove_prefix(pattern.size());
  if (!bench.empty()) {
    if (name.size() < bench.size() + 1 || name[0] != '-' || name.substr(1, bench.size()) != bench) return false;
    name.remove_prefix(bench.size() + 1);
  }
  if (name.empty()) return true;
  if (name[0] != '.' || name.size() < 2) return false;
  return std::all_of(name.begin() + 1, name.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); });
}

namespace {

// The logger's own files in dir (r.files_kept and r.bytes_kept set), or an error in r.
std::vector<LogFileInfo> list_own_files(const std::string& dir, std::string_view prefix, std::string_view bench,
                                        LogPruneResult& r) {
  std::vector<LogFileInfo> files;
  DIR* d = ::opendir(dir.c_str());
  if (!d) {
    r.errors.push_back(fmt::format("cannot list {} for retention: {}", dir, std::strerror(errno)));
    return files;
  }
  while (const dirent* e = ::readdir(d)) {
    const std::string_view name = e->d_name;
    if (!is_own_log_file_name(name, prefix, bench)) continue;
    LogFileInfo f;
    f.path = dir + "/" + std::string(name);
    struct stat st {};
    if (::lstat(f.path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;  // gone meanwhile, or not a file
    f.bytes = st.st_size;
    f.mtime_ns = std::int64_t(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec;
    files.push_back(std::move(f));
  }
  ::closedir(d);
  r.files_kept = static_cast<std::int64_t>(files.size());
  for (const auto& f : files) r.bytes_kept += f.bytes;
  return files;
}

bool delete_file(LogFileInfo&& f, LogPruneResult& r) {
  if (::unlink(f.path.c_str()) != 0 && errno != ENOENT) {
    r.errors.push_back(fmt::format("cannot delete {} (retention): {}", f.path, std::strerror(errno)));
    return false;
  }
  --r.files_kept;
  r.bytes_kept -= f.bytes;
  r.bytes_deleted += f.bytes;
  r.deleted.push_back(std::move(f));
  return true;
}

}  // namespace

LogPruneResult prune_log_files(const std::string& dir, std::string_view prefix, std::string_view bench,
                               const std::string& current, const LogRetentionOptions& options) {
  LogPruneResult r;
  std::vector<LogFileInfo> files = list_own_files(dir, prefix, bench, r);
  for (auto& f : files_to_prune(std::move(files), current, options)) delete_file(std::move(f), r);
  return r;
}

LogPruneResult free_log_space(const std::string& dir, std::string_view prefix, std::string_view bench,
                              const std::string& current, const std::function<bool()>& enough) {
  LogPruneResult r;
  if (enough()) return r;
  std::vector<LogFileInfo> files = list_own_files(dir, prefix, bench, r);
  sort_oldest_first(files);  // every file but the current one may go, the oldest first
  for (auto& f : files) {
    if (f.path == current) continue;
    delete_file(std::move(f), r);
    if (enough()) break;
  }
  return r;
}

}  // namespace spindown
