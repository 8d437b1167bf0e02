// A class's table (fit --table): one row per run across files, CSV and JSON with the same columns.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "spindown/csv_fields.hpp"
#include "spindown/run_table.hpp"

namespace spindown {
namespace {

Parameter param(std::string name, double v, double se, double bench_error = 0) {
  Parameter p{std::move(name), v, se, "", bench_error};
  return p;
}

ModelFit model(ModelKind kind, std::vector<Parameter> params, double rmse) {
  ModelFit m;
  m.kind = kind;
  m.params = std::move(params);
  m.rmse = rmse;
  m.converged = true;
  m.reduced_chi2 = 1.1;
  return m;
}

RunFit run_fit(int number, bool stopped) {
  RunFit f;
  f.run.number = number;
  f.run.cut_index = 100;
  f.run.end_index = 1500;
  f.run.t_cut_s = 8.25;
  f.run.t_stop_s = stopped ? 35.5 : std::nan("");
  f.run.stopped = stopped;
  f.bench.inertia_rel_error = 0.02;
  f.models.push_back(model(ModelKind::viscous, {param("c1", 1.4e-6, 2e-9), param("omega0", 346.6, 0.2)}, 0.06));
  f.models.push_back(model(ModelKind::coulomb, {param("c2", 1.38e-4, 1e-7), param("omega0", 340.1, 0.1)}, 0.007));
  f.models.push_back(model(ModelKind::combined,
                           {param("c3", 1.8e-7, 3e-9, 4e-9), param("c4", 1.14e-4, 2e-7), param("omega0", 346.0, 0.12)},
                           0.004));
  f.best = "combined";
  f.reading_noise = 0.0042;
  return f;
}

std::vector<std::string> split_csv_line(const std::string& line, char delimiter = ',') {
  CsvFieldSplitter splitter;
  std::vector<std::string_view> cells;
  splitter.split(line, delimiter, cells);
  return {cells.begin(), cells.end()};
}

FileFit class_file() {
  FileFit f;
  f.file = "class/bench3_alice.txt";
  f.bench = "bench3";
  f.student = "Alice";
  f.runs.push_back(run_fit(1, true));
  f.runs.push_back(run_fit(2, false));
  f.runs[1].doubts.push_back("readings up to 408 561, a 5 V converter cannot give: is it rpm?");
  f.health.resize(2);
  f.health[0] = HealthVerdict{HealthLevel::service, "friction 3x the baseline", {}, true};
  return f;
}

TEST(RunTable, OneCsvRowPerRunWithTheHeadersColumns) {
  const std::vector<std::string> header = split_csv_line(run_table_csv_header().substr(0, run_table_csv_header().size() - 1));
  std::istringstream rows(run_table_csv_rows(class_file()));
  std::vector<std::vector<std::string>> table;
  for (std::string line; std::getline(rows, line);) table.push_back(split_csv_line(line));
  ASSERT_EQ(table.size(), 2u);
  auto at = [&](std::size_t r, const std::string& col) {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == col) return table[r].at(i);
    ADD_FAILURE() << "no column " << col;
    return std::string();
  };
  for (const auto& r : table) EXPECT_EQ(r.size(), header.size());
  EXPECT_EQ(at(0, "file"), "class/bench3_alice.txt");
  EXPECT_EQ(at(0, "bench"), "bench3");
  EXPECT_EQ(at(0, "student"), "Alice");
  EXPECT_EQ(at(1, "run"), "2");
  EXPECT_EQ(at(0, "best"), "combined");
  EXPECT_DOUBLE_EQ(std::stod(at(0, "c1")), 1.4e-6);  // each model's own coefficient
  EXPECT_DOUBLE_EQ(std::stod(at(0, "c2")), 1.38e-4);
  EXPECT_DOUBLE_EQ(std::stod(at(0, "c3")), 1.8e-7);
  EXPECT_DOUBLE_EQ(std::stod(at(0, "c3_stderr")), 3e-9);
  EXPECT_NEAR(std::stod(at(0, "c3_total_stderr")), 5e-9, 1e-15);  // √(3² + 4²)·1e-9: J's error beside the fit's
  EXPECT_DOUBLE_EQ(std::stod(at(0, "omega0")), 346.0);             // of the best model
  EXPECT_EQ(at(0, "t_stop_s"), "35.5");
  EXPECT_EQ(at(1, "t_stop_s"), "");  // never stopped: an empty cell, not a number
  EXPECT_EQ(at(1, "stopped"), "0");
  EXPECT_EQ(at(0, "trust"), "ok");
  EXPECT_EQ(at(1, "trust"), "doubtful");
  EXPECT_EQ(at(1, "doubts"), "readings up to 408 561, a 5 V converter cannot give: is it rpm?");  // quoted comma kept
  EXPECT_EQ(at(0, "health"), "service");
  EXPECT_EQ(at(0, "health_reason"), "friction 3x the baseline");
  EXPECT_EQ(at(1, "health"), "");  // not assessed
  EXPECT_DOUBLE_EQ(std::stod(at(0, "J_rel_error")), 0.02);
  EXPECT_DOUBLE_EQ(std::stod(at(0, "reading_noise")), 0.0042);  // one noise figure, fit's and explain's σ
}

TEST(RunTable, JsonRowsHaveTheCsvColumnsAndReadBack) {
  FileFit a = class_file();
  FileFit b = class_file();
  b.file = "caf\xe9.txt";  // Latin-1: replaced, never aborts the output
  b.run_bench = {"bench4", "bench4"};  // a run's own bench wins over the file's
  std::string text = "[";
  bool first = true;
  append_run_table_json_rows(a, text, first);
  append_run_table_json_rows(b, text, first);
  text += "\n]";
  const auto rows = nlohmann::json::parse(text);
  ASSERT_EQ(rows.size(), 4u);
  const std::string header = run_table_csv_header();
  std::vector<std::string> names = split_csv_line(header.substr(0, header.size() - 1));
  std::vector<std::string> keys;
  for (const auto& [k, v] : rows[0].items()) keys.push_back(k);
  std::sort(names.begin(), names.end());
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(keys, names);
  EXPECT_EQ(rows[0]["student"], "Alice");
  EXPECT_EQ(rows[2]["bench"], "bench4");
  EXPECT_TRUE(rows[1]["t_stop_s"].is_null());
  EXPECT_EQ(rows[1]["trust"], "doubtful");
  EXPECT_DOUBLE_EQ(rows[0]["c4"].get<double>(), 1.14e-4);
  EXPECT_EQ(rows[3]["file"], "caf\xef\xbf\xbd.txt");
}

// --table json writes the CSV's numbers (10 significant digits) in their shortest form: a time
// computed as 3491 × 0.001 is 3.491, and a fitted coefficient carries no 17-digit tail.
TEST(RunTable, JsonNumbersAreTheCsvsInTheirShortestForm) {
  FileFit f = class_file();
  f.runs[0].run.t_cut_s = 3491 * 0.001;  // 3.4909999999999997 as a double
  f.runs[0].models[2].params[0].value = 1.8053123456789012e-7;
  std::string text = "[";
  bool first = true;
  append_run_table_json_rows(f, text, first);
  EXPECT_NE(text.find("\"t_cut_s\": 3.491,"), std::string::npos) << text;
  EXPECT_NE(text.find("\"c3\": 1.805312346e-07,"), std::string::npos) << text;
  EXPECT_EQ(text.find("3.4909999999999997"), std::string::npos);
  const std::string csv = run_table_csv_rows(f);
  EXPECT_NE(csv.find(",3.491,"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",1.805312346e-07,"), std::string::npos) << csv;
}

TEST(RunTable, AModelThatDidNotConvergeLeavesItsCellsEmpty) {
  FileFit f = class_file();
  f.runs[0].models[2].converged = false;
  f.runs[0].best = "coulomb";
  const std::string rows = run_table_csv_rows(f);
  const std::vector<std::string> cells = split_csv_line(rows.substr(0, rows.find('\n')));
  const std::string header = run_table_csv_header();
  const std::vector<std::string> names = split_csv_line(header.substr(0, header.size() - 1));
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i].rfind("c3", 0) == 0 || names[i].rfind("c4", 0) == 0) {
      EXPECT_EQ(cells[i], "") << names[i];
    }
  }
  EXPECT_DOUBLE_EQ(std::stod(cells[std::find(names.begin(), names.end(), "omega0") - names.begin()]), 340.1);
}

TEST(RunTable, AGermanExcelsCsvWithAByteOrderMark) {
  FileFit f = class_file();
  f.student = "Bj\xC3\xB6rn Sch\xC3\xA4" "fer";
  f.health[0]->reason = "dry friction 1.0\xC3\x97 the baseline; check";
  const CsvStyle de = *csv_style_for_locale("de");
  CsvStyle de_file = de;
  de_file.byte_order_mark = true;
  const std::string header = run_table_csv_header(de_file);
  ASSERT_EQ(header.substr(0, 3), "\xEF\xBB\xBF");  // Excel reads the file as UTF-8, names and "×" right
  const std::vector<std::string> names = split_csv_line(header.substr(3, header.size() - 4), ';');
  const std::string rows = run_table_csv_rows(f, de);
  const std::vector<std::string> cells = split_csv_line(rows.substr(0, rows.find('\n')), ';');
  ASSERT_EQ(cells.size(), names.size());
  auto at = [&](const std::string& col) { return cells[std::find(names.begin(), names.end(), col) - names.begin()]; };
  EXPECT_EQ(at("c3"), "1,8e-07");  // a decimal comma
  EXPECT_EQ(at("t_cut_s"), "8,25");
  EXPECT_EQ(at("run"), "1");
  EXPECT_EQ(at("student"), "Bj\xC3\xB6rn Sch\xC3\xA4" "fer");
  EXPECT_EQ(at("health_reason"), "dry friction 1.0\xC3\x97 the baseline; check");  // quoted: it holds a ';'
  EXPECT_NE(rows.find("\"dry friction 1.0\xC3\x97 the baseline; check\""), std::string::npos);
  // The default: no mark on stdout, ',' and points.
  EXPECT_EQ(run_table_csv_header().substr(0, 5), "file,");
  EXPECT_FALSE(csv_style_for_locale("xx"));
}

}  // namespace
}  // namespace spindown
