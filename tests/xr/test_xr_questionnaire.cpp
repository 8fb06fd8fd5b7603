// The SSQ before and after a play block in a headset, through the real
// Khronos loader on the scripted test runtime: the participant answers each
// symptom with the controllers (A moves the mark from None to Slight, the
// trigger chooses it), the answers are stored with their device, exported
// scored as Kennedy et al. (1993), and the report shows them in its
// Questionnaires section.
#include "../cli/run_cli.hpp"
#include "runtime_env.hpp"
#include "../support/table_protocol.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sqlite3.h>
#include <sstream>
#include <unistd.h>
#include <vector>

namespace {

using curvlab::testing::run_cli;
using curvlab::testing::run_shell;
using curvlab::testing::RuntimeEnv;
namespace fs = std::filesystem;

std::vector<std::vector<std::string>> rows(const std::string& db, const std::string& sql) {
  std::vector<std::vector<std::string>> out;
  sqlite3* handle = nullptr;
  if (sqlite3_open_v2(db.c_str(), &handle, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) return out;
  sqlite3_stmt* stmt = nullptr;
  if (sqlite3_prepare_v2(handle, sql.c_str(), -1, &stmt, nullptr) == SQLITE_OK) {
    while (sqlite3_step(stmt) == SQLITE_ROW) {
      std::vector<std::string> row;
      for (int c = 0; c < sqlite3_column_count(stmt); ++c) {
        const auto* text = sqlite3_column_text(stmt, c);
        row.emplace_back(text ? reinterpret_cast<const char*>(text) : "");
      }
      out.push_back(std::move(row));
    }
  }
  sqlite3_finalize(stmt);
  sqlite3_close(handle);
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A CSV of plain fields (no quotes; lines ending in CRLF, RFC 4180) as
// header → column.
std::vector<std::map<std::string, std::string>> read_plain_csv(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> out;
  const auto split = [](std::string s) {
    if (!s.empty() && s.back() == '\r') s.pop_back();
    std::vector<std::string> f;
    std::stringstream ss(s);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    if (!s.empty() && s.back() == ',') f.emplace_back();
    return f;
  };
  if (std::getline(in, line)) header = split(line);
  while (std::getline(in, line)) {
    const auto f = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < f.size(); ++i) row[header[i]] = f[i];
    out.push_back(std::move(row));
  }
  return out;
}

TEST(XrQuestionnaire, SsqBeforeAndAfterPlayAnsweredWithTheControllersIsScoredInTheExportAndReport) {
  const auto dir = fs::temp_directory_path() / ("curvlab_xr_ssq_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "ssq.toml") << curvlab::test::table_protocol_head("ssq-xr", "x", "y") +
                                         "[[blocks]]\nname = \"ssq_before\"\nkind = \"questionnaire\"\ninstrument = \"ssq\"\n"
                                         "[[blocks]]\nname = \"play\"\nkind = \"play\"\nduration_s = 2\n"
                                         "[[blocks]]\nname = \"ssq_after\"\nkind = \"questionnaire\"\ninstrument = \"ssq\"\n";
  // Every 0.4 s from 1 s after focus: A moves the mark to Slight, and 0.2 s
  // later the trigger chooses it. An item that comes up between an A and
  // its trigger is answered None (its mark never moved).
  RuntimeEnv env(std::map<std::string, std::string>{{"CURVLAB_TEST_XR_PRESS", "right:a@1.0/0.4,right:trigger@1.2/0.4"}});
  const auto db = (dir / "xr.db").string();
  const auto r = run_cli("run " + (dir / "ssq.toml").string() + " --participant X1 --db " + db +
                         " --backend xr --operator-window off --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;

  const auto answers = rows(db, "SELECT b.name, x.item_index, x.value, x.label, x.device, x.rt_ms "
                                "FROM questionnaire_answers x JOIN trials t USING (trial_id) "
                                "JOIN blocks b ON b.block_id = t.block_id ORDER BY b.block_index, x.item_index");
  ASSERT_EQ(answers.size(), 32u) << r.out;
  std::map<std::string, std::vector<int>> values;
  for (const auto& a : answers) {
    values[a[0]].push_back(std::stoi(a[2]));
    EXPECT_EQ(a[4], "xr:right") << a[0] << " item " << a[1];
    EXPECT_EQ(a[3], a[2] == "1" ? "Slight" : "None");
    EXPECT_GT(std::stod(a[5]), 0.0);
  }
  for (const auto& [block, v] : values) {
    ASSERT_EQ(v.size(), 16u) << block;
    // After the first item every item sees its own A and trigger.
    for (std::size_t i = 1; i < v.size(); ++i) EXPECT_EQ(v[i], 1) << block << " item " << i;
  }

  const auto out = dir / "export";
  const auto e = run_cli("export --db " + db + " --out " + out.string() + " --format csv");
  ASSERT_EQ(e.exit_code, 0) << e.out;
  const auto scores = read_plain_csv(out / "questionnaire_scores.csv");
  ASSERT_EQ(scores.size(), 8u);
  const std::map<std::string, std::pair<std::vector<int>, double>> factors{
      {"nausea", {{1, 6, 7, 8, 9, 15, 16}, 9.54}},
      {"oculomotor", {{1, 2, 3, 4, 5, 9, 11}, 7.58}},
      {"disorientation", {{5, 8, 10, 11, 12, 13, 14}, 13.92}}};
  for (const auto& row : scores) {
    SCOPED_TRACE(row.at("block") + " " + row.at("subscale"));
    EXPECT_EQ(row.at("instrument"), "ssq");
    EXPECT_EQ(row.at("participant"), "X1");
    const auto& v = values[row.at("block")];
    const auto raw = [&](const std::string& f) {
      int sum = 0;
      for (int item : factors.at(f).first) sum += v[static_cast<std::size_t>(item - 1)];
      return sum;
    };
    const std::string& s = row.at("subscale");
    const double want = s == "total" ? (raw("nausea") + raw("oculomotor") + raw("disorientation")) * 3.74
                                     : raw(s) * factors.at(s).second;
    EXPECT_NEAR(std::stod(row.at("score")), want, 1e-9);
  }

  if (::access("/usr/bin/Rscript", X_OK) == 0) {
    const auto report = dir / "report";
    const auto rep = run_shell("/usr/bin/Rscript " + std::string(CURVLAB_SOURCE_DIR) + "/analysis/report.R --db " + db +
                               " --out " + report.string() + " --quiet 2>&1");
    ASSERT_EQ(rep.exit_code, 0) << rep.out;
    const std::string html = slurp(report / "report.html");
    EXPECT_NE(html.find("<h2>Questionnaires</h2>"), std::string::npos);
    EXPECT_NE(html.find("<h3>Simulator Sickness Questionnaire</h3>"), std::string::npos);
    EXPECT_NE(html.find("SSQ scores per participant and block"), std::string::npos);
    EXPECT_NE(html.find("Change across exposure"), std::string::npos);
    EXPECT_NE(html.find("ssq_after"), std::string::npos);
  } else {
    std::printf("Rscript not found: the report's part of this test did not run\n");
  }
  fs::remove_all(dir);
}

}  // namespace
