// Retention of spindown-logger's files: the policy (oldest first, both limits, never the file
// being written), which names are the logger's own, and the deletion itself on real files —
// also through EventLogWriter's rotation.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <unistd.h>

#include "spindown/event_log_writer.hpp"
#include "spindown/log_retention.hpp"

namespace spindown {
namespace {

namespace fs = std::filesystem;

std::vector<LogFileInfo> listing() {
  // Sizes 100..500, mtimes out of name order on purpose (oldest: c).
  return {{"d/a", 100, 30}, {"d/b", 200, 20}, {"d/c", 300, 10}, {"d/d", 400, 40}, {"d/e", 500, 50}};
}
std::vector<std::string> paths(const std::vector<LogFileInfo>& v) {
  std::vector<std::string> out;
  for (const auto& f : v) out.push_back(f.path);
  return out;
}

TEST(LogRetention, OffDeletesNothing) {
  EXPECT_TRUE(files_to_prune(listing(), "d/e", {}).empty());
}

TEST(LogRetention, KeepFilesDeletesTheOldestByModificationTime) {
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_files = 3})), (std::vector<std::string>{"d/c", "d/b"}));
  EXPECT_TRUE(files_to_prune(listing(), "d/e", {.keep_files = 5}).empty());
}

TEST(LogRetention, BudgetDeletesOldestUntilTheRestFits) {
  // 1500 bytes in all; a budget of 1000 bytes: c (300) and b (200) go, 1000 left.
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_mb = 1000e-6})), (std::vector<std::string>{"d/c", "d/b"}));
  // 999 bytes: a goes too.
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_mb = 999e-6})),
            (std::vector<std::string>{"d/c", "d/b", "d/a"}));
}

TEST(LogRetention, BothLimitsTheStricterWins) {
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_files = 4, .keep_mb = 1e-3})),
            (std::vector<std::string>{"d/c", "d/b"}));
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_files = 2, .keep_mb = 1e-3})),
            (std::vector<std::string>{"d/c", "d/b", "d/a"}));
}

TEST(LogRetention, NeverTheFileBeingWrittenEvenWhenItIsTheOldest) {
  // c is the oldest, and the one being written (a clock set back, say): it stays, the next go.
  EXPECT_EQ(paths(files_to_prune(listing(), "d/c", {.keep_files = 3})), (std::vector<std::string>{"d/b", "d/a"}));
  // The current file alone over the budget: all others go, it stays.
  EXPECT_EQ(paths(files_to_prune(listing(), "d/e", {.keep_mb = 10e-6})),
            (std::vector<std::string>{"d/c", "d/b", "d/a", "d/d"}));
}

TEST(LogRetention, EqualTimesGoInNameOrder) {
  std::vector<LogFileInfo> same = {{"d/y", 1, 5}, {"d/x", 1, 5}, {"d/z", 1, 5}};
  EXPECT_EQ(paths(files_to_prune(same, "d/z", {.keep_files = 2})), (std::vector<std::string>{"d/x"}));
}

TEST(LogRetention, OnlyTheLoggersOwnNames) {
  EXPECT_TRUE(is_own_log_file_name("lab-2026-11-23-140000.lcm", "lab", ""));
  EXPECT_TRUE(is_own_log_file_name("lab-2026-11-23-140000.3.lcm", "lab", ""));
  EXPECT_TRUE(is_own_log_file_name("lab-2026-11-23-140000-b1.lcm", "lab", "b1"));
  EXPECT_TRUE(is_own_log_file_name("lab-2026-11-23-140000-b1.12.lcm", "lab", "b1"));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000-b1.lcm", "lab", ""));   // another logger's bench
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000.lcm", "lab", "b1"));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000-b2.lcm", "lab", "b1"));
  EXPECT_FALSE(is_own_log_file_name("other-2026-11-23-140000.lcm", "lab", ""));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000.lcm.bak", "lab", ""));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-14000.lcm", "lab", ""));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000.x.lcm", "lab", ""));
  EXPECT_FALSE(is_own_log_file_name("lab-2026-11-23-140000-copy.lcm", "lab", ""));
  EXPECT_FALSE(is_own_log_file_name("lab.lcm", "lab", ""));
}

TEST(LogRetention, OptionsAreChecked) {
  std::string why;
  EXPECT_FALSE((LogRetentionOptions{.keep_files = -1}).is_valid(&why));
  EXPECT_FALSE((LogRetentionOptions{.keep_files = 1}).is_valid(&why));
  EXPECT_NE(why.find("only the file being written"), std::string::npos) << why;
  EXPECT_FALSE((LogRetentionOptions{.keep_mb = -2}).is_valid(&why));
  EXPECT_TRUE((LogRetentionOptions{.keep_files = 2, .keep_mb = 5}).is_valid(&why));
}

class RetentionDir : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("spindown-retention-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  void make(const std::string& name, std::size_t bytes, int age_s) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << std::string(bytes, 'x');
    fs::last_write_time(p, fs::file_time_type::clock::now() - std::chrono::seconds(age_s));
  }
  void make_four_own_logs() {
    for (int h = 0; h < 4; ++h) make("lab-2026-01-01-0" + std::to_string(h) + "0000.lcm", 1000, 400 - 100 * h);
  }
  std::set<std::string> names() const {
    std::set<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.insert(e.path().filename().string());
    return out;
  }
  fs::path dir_;
};

TEST_F(RetentionDir, DeletesOnlyOwnOldestFiles) {
  make_four_own_logs();  // an hour apart, 1000 bytes each
  make("notes.txt", 5000, 1000);
  make("other-2026-01-01-000000.lcm", 5000, 1000);
  make("lab-2026-01-01-000000-b1.lcm", 5000, 1000);
  const std::string current = dir_.string() + "/lab-2026-01-01-030000.lcm";
  const LogPruneResult r = prune_log_files(dir_.string(), "lab", "", current, {.keep_mb = 2500e-6});
  EXPECT_TRUE(r.errors.empty());
  ASSERT_EQ(r.deleted.size(), 2u);
  EXPECT_EQ(r.bytes_deleted, 2000);
  EXPECT_EQ(r.files_kept, 2);
  EXPECT_EQ(r.bytes_kept, 2000);
  EXPECT_EQ(names(), (std::set<std::string>{"lab-2026-01-01-020000.lcm", "lab-2026-01-01-030000.lcm", "notes.txt",
                                            "other-2026-01-01-000000.lcm", "lab-2026-01-01-000000-b1.lcm"}));
}

// A disk about to fill (issue 31): its own files go, oldest first, one at a time until there is
// room, whatever the budget; never the current file nor another's.
TEST_F(RetentionDir, FreeingSpaceDeletesOwnOldestUntilThereIsRoom) {
  make_four_own_logs();  // an hour apart, 1000 bytes each
  make("notes.txt", 5000, 1000);
  const std::string current = dir_.string() + "/lab-2026-01-01-030000.lcm";
  int asked = 0;
  LogPruneResult r = free_log_space(dir_.string(), "lab", "", current, [&] { return ++asked > 2; });
  EXPECT_TRUE(r.errors.empty());
  EXPECT_EQ(r.deleted.size(), 2u) << "room after two files";
  EXPECT_EQ(names(), (std::set<std::string>{"lab-2026-01-01-020000.lcm", "lab-2026-01-01-030000.lcm", "notes.txt"}));
  r = free_log_space(dir_.string(), "lab", "", current, [] { return false; });  // never enough
  EXPECT_EQ(r.deleted.size(), 1u);
  EXPECT_EQ(names(), (std::set<std::string>{"lab-2026-01-01-030000.lcm", "notes.txt"}));
  r = free_log_space(dir_.string(), "lab", "", current, [] { return true; });  // room already
  EXPECT_TRUE(r.deleted.empty());
}

TEST_F(RetentionDir, MissingDirectoryIsAnErrorNamingIt) {
  const LogPruneResult r = prune_log_files((dir_ / "gone").string(), "lab", "", "", {.keep_files = 2});
  ASSERT_EQ(r.errors.size(), 1u);
  EXPECT_NE(r.errors[0].find("gone"), std::string::npos) << r.errors[0];
}

TEST_F(RetentionDir, WriterPrunesAtEachRotationAndKeepsTheCurrentFile) {
  EventLogWriterOptions o;
  o.dir = dir_.string();
  o.prefix = "lab";
  o.rotate_size_mb = 0.002;  // a new file every ~2 kB
  o.retention.keep_files = 3;
  make("notes.txt", 10, 1000);
  std::int64_t now = 1'700'000'000'000'000;
  EventLogWriter w(o, now);
  w.open(now);
  const std::string payload(500, 'p');
  for (int i = 0; i < 60; ++i) {
    now += 1'000'000;  // a second apart: each file its own name
    ASSERT_TRUE(w.write(now, "SPINDOWN.x.OTHER", payload.data(), static_cast<std::int32_t>(payload.size()), now));
    w.flush(now);
  }
  ASSERT_GE(w.files().size(), 8u);
  EXPECT_EQ(w.counters().files_deleted, static_cast<std::int64_t>(w.files().size()) - 3);
  EXPECT_EQ(w.deleted_files().size(), w.files().size() - 3);
  // What is left: the three newest, the current one among them, and the unrelated file.
  std::set<std::string> want = {"notes.txt"};
  for (std::size_t i = w.files().size() - 3; i < w.files().size(); ++i)
    want.insert(fs::path(w.files()[i]).filename().string());
  EXPECT_EQ(names(), want);
  EXPECT_TRUE(fs::exists(w.current_path()));
  // The first files went first.
  EXPECT_EQ(w.deleted_files().front(), w.files().front());
  const status_t st = w.make_status(now);
  bool found = false;
  for (int i = 0; i < st.ncounters; ++i)
    if (st.counter_name[i] == "files_deleted") {
      found = true;
      EXPECT_EQ(st.counter_value[i], w.counters().files_deleted);
    }
  EXPECT_TRUE(found) << "files_deleted in the heartbeat";
  w.close(now);
}

TEST_F(RetentionDir, ANameRetentionFreedIsNotTakenAgain) {
  // Many files within one second, the oldest deleted as they go: the suffixes only go up, so the
  // names keep the order the files were written in (no second "lab-….lcm" after ".3").
  EventLogWriterOptions o;
  o.dir = dir_.string();
  o.prefix = "lab";
  o.rotate_size_mb = 0.002;
  o.retention.keep_files = 2;
  const std::int64_t now = 1'700'000'000'000'000;  // one second for every file
  EventLogWriter w(o, now);
  w.open(now);
  const std::string payload(500, 'p');
  for (int i = 0; i < 30; ++i) {
    ASSERT_TRUE(w.write(now, "SPINDOWN.x.OTHER", payload.data(), static_cast<std::int32_t>(payload.size()), now));
    w.flush(now);
  }
  ASSERT_GE(w.files().size(), 5u);
  std::set<std::string> unique(w.files().begin(), w.files().end());
  EXPECT_EQ(unique.size(), w.files().size()) << "a file name used twice";
  EXPECT_EQ(fs::path(w.files()[3]).filename().string(), event_log_file_name("lab", "", now / 1000000, 3));
  w.close(now);
}

}  // namespace
}  // namespace spindown
