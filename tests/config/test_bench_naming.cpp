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

// Moodle's submissions unzipped on a Mac: folders named in NFD ("u" + combining diaeresis); the
// roster typed on Windows (NFC), or the other way round (names pasted from Finder). Both students
// of one file name are found by their folders, with their names in NFC; "give its folder too" is
// not said when the folder is given.
TEST_F(BenchNamingTest, NamesAreComparedAfterUnicodeNormalisation) {
  const std::string nfc_name = "J\xc3\xbcrgen", nfd_name = "Ju\xcc\x88rgen";
  fs::create_directories(dir / "class" / nfd_name);
  fs::create_directories(dir / "class" / "Zoe");
  const std::string roster = write("roster.csv", "file,bench,student\n"
                                                 "class/" + nfc_name + "/putty.log,bench3," + nfc_name + "\n"
                                                 "class/Zoe/putty.log,bench1,Zoe\n");
  const BenchNaming naming(roster, "");
  const BenchName j = naming.name((dir / "class" / nfd_name / "putty.log").string());
  EXPECT_EQ(j.bench, "bench3") << j.problem;
  EXPECT_EQ(j.student, nfc_name);
  EXPECT_TRUE(j.problem.empty()) << j.problem;
  const BenchName z = naming.name((dir / "class" / "Zoe" / "putty.log").string());
  EXPECT_EQ(z.bench, "bench1");
  // The roster in NFD, the folders in NFC: the same.
  const std::string roster2 = write("roster2.csv", "file,bench,student\nclass/" + nfd_name + "/putty.log,bench3," +
                                                       nfd_name + "\n");
  const BenchNaming naming2(roster2, "");
  const BenchName j2 = naming2.name((dir / "class" / nfc_name / "putty.log").string());
  EXPECT_EQ(j2.bench, "bench3") << j2.problem;
  EXPECT_EQ(j2.student, nfc_name);
}

TEST_F(BenchNamingTest, SpreadsheetExportsAreRead) {
  // Semicolons (a European spreadsheet), a byte-order mark, CR LF, other columns, another order.
  const std::string roster =
      write("roster.csv", "\xEF\xBB\xBFStudent;Group;Bench;File\r\nAnna;A;b7;anna.tsv\r\n");
  const BenchName n = BenchNaming(roster, "").name("anna.tsv");
  EXPECT_EQ(n.bench, "b7");
  EXPECT_EQ(n.student, "Anna");
}

TEST_F(BenchNamingTest, AGermanExcelsCsvIsReadWithItsNames) {
  // Excel (German) "CSV (Trennzeichen-getrennt)": Windows-1252, ';', CR LF, every row padded to the
  // sheet's used range, its empty rows as ';;;;' — after the data and between.
  const std::string roster = write("roster.csv",
                                   "file;bench;student;;\r\n"
                                   "mueller.txt;bench1;M\xFCller, J\xFCrgen;;\r\n"
                                   ";;;;\r\n"
                                   "schaefer.txt;bench3;Bj\xF6rn Sch\xE4" "fer;;\r\n"
                                   "weiss.txt;bench2;Anna Wei\xDF;;\r\n"
                                   ";;;;\r\n;;;;\r\n;;;;\r\n");
  const ClassRoster r = load_class_roster(roster);
  ASSERT_EQ(r.entries.size(), 3u);
  const BenchNaming naming(roster, "");
  EXPECT_EQ(naming.name("mueller.txt").student, "M\xC3\xBCller, J\xC3\xBCrgen");
  EXPECT_EQ(naming.name("schaefer.txt").student, "Bj\xC3\xB6rn Sch\xC3\xA4" "fer");
  EXPECT_EQ(naming.name("weiss.txt").student, "Anna Wei\xC3\x9F");
  EXPECT_EQ(naming.name("weiss.txt").bench, "bench2");
  EXPECT_EQ(naming.name("weiss.txt").from, "roster " + roster + ":5");
}

TEST_F(BenchNamingTest, ExcelsUnicodeTextAndItsSeparatorHintAreRead) {
  // "Unicode Text (*.txt)": UTF-16 LE with a byte-order mark, tabs, CR LF.
  std::string utf16("\xFF\xFE", 2);
  for (char16_t c : std::u16string(u"Datei\tPr\u00FCfstand\tName\r\nweiss.txt\tbench2\tAnna Wei\u00DF\r\n")) {
    utf16 += static_cast<char>(c & 0xFF);
    utf16 += static_cast<char>(c >> 8);
  }
  const BenchName n = BenchNaming(write("roster.txt", utf16), "").name("weiss.txt");
  EXPECT_EQ(n.bench, "bench2");
  EXPECT_EQ(n.student, "Anna Wei\xC3\x9F");
  // "sep=," first: Excel's hint for the delimiter, though the header has a ';' in a name.
  const BenchName s =
      BenchNaming(write("sep.csv", "sep=,\nfile,bench,student,note;x\na.txt,b1,\"Kim; Lee\",\n"), "").name("a.txt");
  EXPECT_EQ(s.student, "Kim; Lee");
}

TEST_F(BenchNamingTest, AWorkbookOrUndecodableBytesAreRefusedWithWhatToDo) {
  auto message = [&](const std::string& name, const std::string& bytes) {
    try {
      load_class_roster(write(name, bytes));
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  // The first bytes of an .xlsx as Excel writes it: a zip whose first entry is [Content_Types].xml.
  std::string xlsx("PK\x03\x04\x14\x00\x06\x00\x08\x00\x00\x00\x21\x00", 14);
  xlsx.append(12, '\x01').append("\x13\x00\x00\x00", 4).append("[Content_Types].xml");
  const std::string w = message("roster.xlsx", xlsx);
  EXPECT_NE(w.find("an Excel workbook (.xlsx)"), std::string::npos) << w;
  EXPECT_NE(w.find("save it as CSV (UTF-8)"), std::string::npos) << w;
  EXPECT_EQ(w.find("binary"), std::string::npos) << w;
  // UTF-8 and Windows-1252 in one file: no one encoding reads every name right.
  const std::string mixed = message("mixed.csv", "file,bench,student\na.txt,b1,J\xC3\xBCrgen\nb.txt,b2,J\xFCrgen\n");
  EXPECT_NE(mixed.find("CSV UTF-8"), std::string::npos) << mixed;
  EXPECT_NE(message("nul.csv", std::string(200, '\0')).find("binary data"), std::string::npos);
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

namespace spindown {
namespace {

// A Canvas gradebook export made into a roster: a byte-order mark, "Müller, Anna" quoted, a
// "Points Possible" row and a test student without a file. Rows without a file are skipped and
// named; the rest is read (before: refused, exit 2, until hand-edited).
TEST_F(BenchNamingTest, RowsWithoutAFileAreSkippedAndNamed) {
  const std::string roster = write("canvas.csv", "\xEF\xBB\xBFStudent,ID,file,bench\n"
                                                 "Points Possible,,,\n"
                                                 "\"M\xC3\xBCller, Anna\",101,anna.txt,bench1\n"
                                                 "\"Student, Test\",999,,\n");
  const BenchNaming naming(roster, "");
  const BenchName a = naming.name((dir / "anna.txt").string());
  EXPECT_EQ(a.bench, "bench1") << a.problem;
  ASSERT_EQ(naming.roster_skipped().size(), 2u);
  EXPECT_NE(naming.roster_skipped()[0].find(":2: no file (Points Possible): skipped"), std::string::npos)
      << naming.roster_skipped()[0];
  EXPECT_NE(naming.roster_skipped()[1].find("(Student, Test)"), std::string::npos) << naming.roster_skipped()[1];
}

}  // namespace
}  // namespace spindown

namespace spindown {
namespace {

// Two students' putty.log listed by folder; a third putty.log from a folder the roster does not
// list is never put on a bench made up of its name ("putty", which merged two benches' students).
TEST_F(BenchNamingTest, ANameSeveralFilesShareIsNoBench) {
  const std::string roster = write("roster.csv", "file,bench,student\nclass/anna/putty.log,bench1,Anna\n"
                                                 "class/ben/putty.log,bench2,Ben\n");
  const BenchNaming naming(roster, "");
  EXPECT_EQ(naming.name((dir / "class" / "ben" / "putty.log").string()).bench, "bench2");
  const BenchName stray = naming.name((dir / "class" / "carl" / "putty.log").string(), "putty");
  EXPECT_EQ(stray.bench, "");
  EXPECT_NE(stray.problem.find("several files named 'putty.log'"), std::string::npos) << stray.problem;
  EXPECT_NE(stray.problem.find("no bench"), std::string::npos) << stray.problem;
}

}  // namespace
}  // namespace spindown
