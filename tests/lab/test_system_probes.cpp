// What `spindown doctor` asks of this machine (system_probes.hpp): files, programs and their
// output, interfaces; "unknown" answers instead of exceptions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <string>
#include <unistd.h>

#include "spindown/system_probes.hpp"

namespace spindown {
namespace {

TEST(SystemProbes, FilesAndNumbers) {
  const std::string path = ::testing::TempDir() + "spindown_probe_" + std::to_string(::getpid());
  std::ofstream(path) << "212992\n";
  EXPECT_EQ(read_long(path), 212992);
  EXPECT_EQ(read_file(path), std::optional<std::string>("212992\n"));
  std::ofstream(path) << "not a number\n";
  EXPECT_EQ(read_long(path), std::nullopt);
  std::remove(path.c_str());
  EXPECT_EQ(read_file("/nonexistent/spindown"), std::nullopt);
  EXPECT_EQ(read_long("/nonexistent/spindown"), std::nullopt);
}

TEST(SystemProbes, ProgramsAndTheirOutput) {
  const std::string sh = find_program("sh");
  ASSERT_FALSE(sh.empty());
  EXPECT_EQ(find_program("no-such-program-spindown"), "");
  std::string why;
  EXPECT_EQ(capture({sh, "-c", "echo hello"}, &why), std::optional<std::string>("hello\n"));
  EXPECT_EQ(capture({sh, "-c", "echo broken >&2; exit 3"}, &why), std::nullopt);
  EXPECT_EQ(why, "broken");
  EXPECT_EQ(capture({sh, "-c", "exit 4"}, &why), std::nullopt);
  EXPECT_EQ(why, "exit status 4");
}

TEST(SystemProbes, LoopbackIsAnInterface) {
  const auto ifs = read_interfaces();
  EXPECT_TRUE(std::any_of(ifs.begin(), ifs.end(), [](const NetInterface& i) { return i.name == "lo"; }));
  EXPECT_TRUE(std::is_sorted(ifs.begin(), ifs.end(), [](const auto& a, const auto& b) { return a.name < b.name; }));
}

}  // namespace
}  // namespace spindown
