#include "spindown/toml_file.hpp"

#include <filesystem>
#include <fmt/format.h>
#include <stdexcept>

namespace spindown {

toml::table parse_toml_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error(fmt::format("{}: cannot read: not a file or does not exist", path));
  try {
    return toml::parse_file(path);
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw std::runtime_error(fmt::format("{}:{}:{}: {}", path, where.line, where.column, e.description()));
  }
}

}  // namespace spindown
