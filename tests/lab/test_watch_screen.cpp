// watch_screen: one redraw of `spindown watch` on a terminal of a given size.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "lab_messages.hpp"
#include "spindown/watch_screen.hpp"

namespace spindown {
namespace {

constexpr std::int64_t t0 = 1'700'000'000'000'000;

// The lab table test's fit with a verdict and a long reason.
fit_t fit_msg(const std::string& bench, int run, const std::string& verdict) {
  fit_t m = test::fit_msg(bench, run);
  m.verdict = verdict;
  m.verdict_reason = "dry friction 2.2× the baseline (±0.0029): check bearings and alignment; stops 51 % sooner";
  return m;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// Long events (a fit's full line, a health reason) under a table of three benches on 80×32 and
// 120×40: every line fits, the screen never scrolls, title, header and every row stay, and the
// events take what is left, folded.
TEST(WatchScreen, TableStaysEventsFoldWithinTheSize) {
  LabTable table;
  std::vector<std::string> events;
  for (int b = 0; b < 3; ++b) {
    const std::string id = "teaching-lab-bench-00" + std::to_string(b);
    table.on_fit(id, fit_msg(id, 4, b == 1 ? "check" : "ok"), t0);
  }
  for (int i = 0; i < 30; ++i)
    events.push_back("teaching-lab-bench-001: run 4 fit: best combined: c3 = (1.822 ± 0.011)e-07 N·m·s/rad, c4 = "
                     "(1.139 ± 0.002)e-04 N·m, RMSE 0.0123 V; health check: dry friction 2.2× the baseline, event " +
                     std::to_string(i));
  for (const auto& [cols, rows] : {std::pair<std::size_t, std::size_t>{80, 32}, {120, 40}, {80, 12}}) {
    const auto lines = lines_of(watch_screen(table, t0, events, {cols, rows, 12}));
    ASSERT_FALSE(lines.empty());
    EXPECT_LE(lines.size(), rows - 1) << cols << "x" << rows;  // the last row stays free: no scrolling
    EXPECT_TRUE(lines[0].starts_with("spindown watch")) << lines[0];
    EXPECT_TRUE(lines[1].starts_with("BENCH")) << lines[1];
    for (int b = 0; b < 3; ++b) {
      const std::string& row = lines[2 + static_cast<std::size_t>(b)];
      EXPECT_TRUE(row.starts_with("teaching-lab-bench-00" + std::to_string(b))) << row;
      EXPECT_NE(row.find("1.822±0.011  1.1390±0.0020"), std::string::npos) << row;
      EXPECT_TRUE(row.ends_with(b == 1 ? "CHECK" : "OK")) << row;
    }
    for (const auto& line : lines) EXPECT_LT(display_width(line), cols) << line;
    const auto area = std::find(lines.begin(), lines.end(), "recent events:");
    ASSERT_NE(area, lines.end()) << cols << "x" << rows;
    // The newest event is the last line; an event folded to two lines at most.
    EXPECT_TRUE(lines.back().ends_with("event 29") || lines.back().ends_with("…")) << lines.back();
    EXPECT_LE(std::count_if(area, lines.end(), [](const std::string& l) { return l.ends_with("…"); }),
              std::count_if(area, lines.end(), [](const std::string& l) { return l.starts_with("  teaching"); }));
  }
}

TEST(WatchScreen, FoldKeepsWordsAndCutsTheLastLine) {
  EXPECT_EQ(fold_to_width("short", 20, 2), "short\n");
  EXPECT_EQ(fold_to_width("one two three four", 10, 2), "one two\n    three…\n");
  EXPECT_EQ(fold_to_width("one two three four", 10, 3), "one two\n    three\n    four\n");
  EXPECT_EQ(fold_to_width("abcdefghijkl", 5, 1), "abcd…\n");
  EXPECT_EQ(fold_to_width("c3 = 1 ± 2 g·cm² and more", 12, 1), "c3 = 1 ± 2 …\n");  // code points, not bytes
}

}  // namespace
}  // namespace spindown
