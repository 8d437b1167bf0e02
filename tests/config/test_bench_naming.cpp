// Which bench (and student) a class's text file is from: a roster, a file-name pattern, --bench.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <unistd.h>

#include "spindown/bench_naming.hpp"

namespace spindown {
namespace {

namespace fs = std::filesystem;

class BenchNamingTest : public ::testing::Test {
 protected:
  fs::path dir = fs::temp_directory_path() / ("spindown-naming-" + std::to_string(::getpid()));
  void SetUp() override { fs::create_directories(dir / "class"); }
  void TearDown() override { fs::remove_all(dir); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }
};

TEST_F(BenchNamingTest, RosterNamesBenchAndStudentByPathOrFileName) {
  const std::string roster = write("roster.csv",
                                   "# week 3\n"
                                   "file,bench,student\n"
                                   "class/alice.txt,bench1,Alice\n"
                                   "bob.txt,bench2,\"Smith, Bob\"\n");
  const BenchNaming naming(roster, "");
  ASSERT_TRUE(naming.active());
  // Relative to the roster's folder, from wherever the command runs.
  const BenchName a = naming.name((dir / "class" / "alice.txt").string());
  EXPECT_EQ(a.bench, "bench1");
  EXPECT_EQ(a.student, "Alice");
  EXPECT_EQ(a.from, "roster " + roster + ":3");
  EXPECT_TRUE(a.problem.empty());
  // By the file name alone; a quoted field keeps its comma.
  const BenchName b = naming.name("/elsewhere/bob.txt");
  EXPECT_EQ(b.bench, "bench2");
  EXPECT_EQ(b.student, "Smith, Bob");
}

TEST_F(BenchNamingTest, SpreadsheetExportsAreRead) {
  // Semicolons (a European spreadsheet), a byte-order mark, CR LF, other columns, another order.
  const std::string roster =
      write("roster.csv", "\xEF\xBB\xBFStudent;Group;Bench;File\r\nAnna;A;b7;anna.tsv\r\n");
  const BenchName n = BenchNaming(roster, "").name("anna.tsv");
  EXPECT_EQ(n.bench, "b7");
  EXPECT_EQ(n.student, "Anna");
}

TEST_F(BenchNamingTest, FileNotInRosterIsSaidAndKeepsItsOwnName) {
  const std::string roster = write("roster.csv", "file,bench\nalice.txt,bench1\n");
  const BenchName n = BenchNaming(roster, "").name("carol.txt", "carol");
  EXPECT_EQ(n.bench, "carol");
  EXPECT_NE(n.problem.find("not in the roster"), std::string::npos) << n.problem;
  EXPECT_NE(n.problem.find("carol"), std::string::npos) << n.problem;
}

TEST_F(BenchNamingTest, BadRostersNameFileAndLine) {
  auto message = [&](const std::string& text) {
    const std::string path = write("bad.csv", text);
    try {
      load_class_roster(path);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("file,student\na.txt,Al\n").find("bad.csv:1: the header"), std::string::npos);
  EXPECT_NE(message("file,bench\na.txt,bench 1\n").find("bad.csv:2: bench 'bench 1'"), std::string::npos);
  EXPECT_NE(message("file,bench\na.txt,b1\na.txt,b2\n").find("bad.csv:3: 'a.txt' is bench 'b2' here but bench 'b1' on line 2"),
            std::string::npos);
  EXPECT_NE(message("file,bench,student\na.txt\n").find("bad.csv:2: 1 field where the header has 3"),
            std::string::npos);
  EXPECT_NE(message("").find("empty"), std::string::npos);
  EXPECT_THROW(load_class_roster((dir / "missing.csv").string()), std::runtime_error);
}

TEST_F(BenchNamingTest, PatternTakesBenchThenStudentFromTheFileNameOnly) {
  const BenchNaming naming("", "(bench[0-9]+)_([a-z]+)");
  const BenchName n = naming.name("bench3_data/bench12_alice.txt");
  EXPECT_EQ(n.bench, "bench12");  // the name, never a folder
  EXPECT_EQ(n.student, "alice");
  EXPECT_EQ(n.from, "--bench-pattern");
  const BenchName miss = naming.name("notes.txt", "notes");
  EXPECT_EQ(miss.bench, "notes");
  EXPECT_NE(miss.problem.find("does not match --bench-pattern"), std::string::npos) << miss.problem;
}

TEST_F(BenchNamingTest, RosterBeforePatternBeforeFixedBench) {
  const std::string roster = write("roster.csv", "file,bench\nbench9_x.txt,special\n");
  const BenchNaming naming(roster, "(bench[0-9]+)", "room");
  EXPECT_EQ(naming.name("bench9_x.txt").bench, "special");
  EXPECT_EQ(naming.name("bench4_y.txt").bench, "bench4");
  const BenchName fixed = naming.name("other.txt");
  EXPECT_EQ(fixed.bench, "room");
  EXPECT_EQ(fixed.from, "--bench");
}

TEST_F(BenchNamingTest, BadPatternsAreRefusedWithTheOption) {
  EXPECT_THROW(BenchNaming("", "(unclosed"), std::invalid_argument);
  try {
    BenchNaming("", "bench[0-9]+");
    FAIL() << "a pattern without a group was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("has no group"), std::string::npos);
  }
  EXPECT_THROW(BenchNaming("", "", "no spaces"), std::invalid_argument);
  EXPECT_FALSE(BenchNaming().active());
}

TEST(FileStem, DropsFoldersAndTheLastExtension) {
  EXPECT_EQ(file_stem("runs/bench3.txt"), "bench3");
  EXPECT_EQ(file_stem("a.b.tsv"), "a.b");
  EXPECT_EQ(file_stem(".hidden"), ".hidden");
}

}  // namespace
}  // namespace spindown
