// Reading TOML files: errors name the file, line and column, or say the file is not readable.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "spindown/toml_file.hpp"

using namespace spindown;

namespace {

std::string message_of(const std::string& path) {
  try {
    parse_toml_file(path);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / ("spindown-toml-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(TomlFile, ReadsAGoodFile) {
  const auto path = (temp_dir() / "good.toml").string();
  std::ofstream(path) << "bench_id = \"b1\"\n[bench]\ninertia_kg_m2 = 1.2e-5\n";
  const toml::table t = parse_toml_file(path);
  EXPECT_EQ(t["bench_id"].value_or(std::string()), "b1");
  EXPECT_DOUBLE_EQ(t["bench"]["inertia_kg_m2"].value_or(0.0), 1.2e-5);
}

TEST(TomlFile, SyntaxErrorNamesFileLineAndColumn) {
  const auto path = (temp_dir() / "bad.toml").string();
  std::ofstream(path) << "bench_id = \"b1\"\n[bench\n";
  const std::string msg = message_of(path);
  EXPECT_EQ(msg.rfind(path + ":2:", 0), 0u) << msg;
}

TEST(TomlFile, MissingFileOrDirectoryIsNotReadable) {
  const auto dir = temp_dir();
  EXPECT_NE(message_of((dir / "absent.toml").string()).find("cannot read"), std::string::npos);
  EXPECT_NE(message_of(dir.string()).find("cannot read"), std::string::npos);
}

}  // namespace
