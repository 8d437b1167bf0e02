#include "spindown/bench_file.hpp"

#include <algorithm>
#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>
#include <toml++/toml.h>

#include "spindown/bridge_settings.hpp"
#include "spindown/health_file.hpp"
#include "spindown/lcm_channels.hpp"
#include "spindown/toml_file.hpp"

namespace spindown {

namespace {

// One parameter by the rule: the command line's (already in p), else the file's, else the CONFIG's.
// source: where the value came from, for reports (nullptr: an uncertainty, which has none of its own).
void choose_one(bool given, bool file_sets, const BenchFile* file, const std::optional<BenchParams>& config,
                double BenchParams::*value, std::string BenchParams::*source, BenchParams& p) {
  if (given) return;
  if (file && file_sets) {
    p.*value = file->params.*value;
    if (source) p.*source = file->params.*source + " (" + file->path + ")";
  } else if (config) {
    p.*value = (*config).*value;
    if (source) p.*source = (*config).*source;
  }
}

}  // namespace

BenchParams choose_bench_params(const BenchChoice& cli, const BenchFile* file, const std::optional<BenchParams>& config) {
  BenchParams p = cli.given;  // the command line's values, the lab's where it gave none
  choose_one(cli.inertia_given, file && file->sets_inertia, file, config, &BenchParams::inertia_kg_m2,
             &BenchParams::inertia_source, p);
  choose_one(cli.kb_given, file && file->sets_kb, file, config, &BenchParams::kb_v_s_per_rad, &BenchParams::kb_source,
             p);
  choose_one(cli.inertia_error_given, file && file->sets_inertia_error, file, config, &BenchParams::inertia_rel_error,
             nullptr, p);
  choose_one(cli.kb_error_given, file && file->sets_kb_error, file, config, &BenchParams::kb_rel_error, nullptr, p);
  return p;
}

BenchFile load_bench_file(const std::string& path) {
  BenchFile f;
  f.path = path;
  f.health = load_motor_health_config(path);  // checks the file exists and parses, names file and key
  f.bench = bench_id_of_config(path);
  std::string why;
  if (!is_valid_bench_id(f.bench, &why))
    throw std::runtime_error(fmt::format("{}: bench id '{}' (bench_id key or file name): {}", path, f.bench, why));
  BridgeSettings s;
  load_bridge_settings(path, s);  // [bench] exactly as spindown-bridge reads it
  f.params = s.params;
  f.warnings = std::move(s.warnings);
  const toml::table root = parse_toml_file(path);
  f.sets_inertia = root.at_path("bench.inertia_kg_m2").node() || root.at_path("bench.flywheel_radius_m").node();
  f.sets_kb = root.at_path("bench.kb_v_s_per_rad").node() || root.at_path("bench.speed_constant_rpm_per_v").node();
  f.sets_inertia_error = root.at_path("bench.inertia_error_pct").node() != nullptr;
  f.sets_kb_error = root.at_path("bench.kb_error_pct").node() != nullptr;
  return f;
}

const BenchFile* BenchFiles::for_bench(std::string_view bench) const {
  if (!bench.empty()) {
    const auto it = files.find(bench);
    return it == files.end() ? nullptr : &it->second;
  }
  return files.size() == 1 ? &files.begin()->second : nullptr;
}

BenchFiles load_bench_files(const std::vector<std::string>& paths) {
  BenchFiles out;
  auto add = [&](const std::string& path) {
    BenchFile f = load_bench_file(path);
    if (auto it = out.files.find(f.bench); it != out.files.end())
      throw std::runtime_error(
          fmt::format("{}: bench '{}' is already described by {}", path, f.bench, it->second.path));
    std::string id = f.bench;
    out.files.emplace(std::move(id), std::move(f));
  };
  for (const auto& p : paths) {
    std::error_code ec;
    if (std::filesystem::is_directory(p, ec)) {
      std::vector<std::string> found;
      for (const auto& e : std::filesystem::directory_iterator(p, ec))
        if (e.path().extension() == ".toml" && e.is_regular_file(ec)) found.push_back(e.path().string());
      if (ec) throw std::runtime_error(fmt::format("{}: cannot list: {}", p, ec.message()));
      std::sort(found.begin(), found.end());
      if (found.empty()) throw std::runtime_error(fmt::format("{}: no *.toml bench files in this directory", p));
      for (const auto& f : found) add(f);
    } else {
      add(p);
    }
  }
  return out;
}

}  // namespace spindown
