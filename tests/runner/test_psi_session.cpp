// The psi example protocol (protocols/stick_pse_psi.toml) as a user runs it:
// a whole headless session answered by the simulated observer stores the
// posterior after every psi answer, which another program (the sqlite3
// shell) reads back, and the export carries it; a session ended half-way and
// resumed shows the same values and reaches the same estimates as one run
// without a break.
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using curvlab::testing::run_shell;

namespace {

const std::string kPsi = std::string(CURVLAB_SOURCE_DIR) + "/protocols/stick_pse_psi.toml";

// Rows of the sqlite3 shell's output ('|' between columns).
std::vector<std::vector<std::string>> shell_rows(const std::string& db, const std::string& sql) {
  const auto r = run_shell("sqlite3 -readonly '" + db + "' \"" + sql + "\" 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  std::vector<std::vector<std::string>> rows;
  std::istringstream lines(r.out);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::istringstream fields(line);
    std::string cell;
    while (std::getline(fields, cell, '|')) cells.push_back(cell);
    if (!line.empty() && line.back() == '|') cells.emplace_back();
    rows.push_back(std::move(cells));
  }
  return rows;
}

// What a psi session's trials, steps and posteriors say, in trial order.
const std::string kTrials =
    "SELECT trial_index, conditions, status, COALESCE(end_reason, ''), COALESCE(response, ''), "
    "COALESCE(json_extract(stimulus, '$.stick_sagitta_m'), '') FROM trials ORDER BY trial_index";
const std::string kSteps =
    "SELECT st.staircase, st.step_index, st.intensity, st.response_correct, st.next_intensity, "
    "json_extract(e.detail, '$.pse_mean'), json_extract(e.detail, '$.pse_sd'), "
    "json_extract(e.detail, '$.slope_mean'), json_extract(e.detail, '$.entropy_nats') "
    "FROM staircase_steps st JOIN events e ON e.trial_id = st.trial_id AND e.kind = 'posterior' "
    "ORDER BY st.staircase, st.step_index";

}  // namespace

TEST(PsiSession, AHeadlessSessionStoresThePosteriorOfEveryAnswer) {
  const auto dir = fresh_dir("psi_session");
  const auto db = (dir / "psi.sqlite").string();
  const auto r = run_cli("run " + kPsi + " --participant P01 --db " + db + " --render none --quiet --export " +
                         (dir / "export").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;

  // Read by a second program, as an analyst's would: one posterior per
  // answered psi trial, next to its step.
  EXPECT_EQ(shell_rows(db, "SELECT status FROM sessions")[0][0], "completed");
  const auto answered = shell_rows(db, "SELECT COUNT(*) FROM trials t JOIN blocks b ON b.block_id = t.block_id "
                                       "WHERE b.name = 'main' AND t.status = 'completed'");
  const auto posteriors = shell_rows(db, "SELECT COUNT(*), COUNT(DISTINCT trial_id) FROM events WHERE kind = 'posterior'");
  EXPECT_EQ(posteriors[0][0], answered[0][0]);
  EXPECT_EQ(posteriors[0][1], answered[0][0]);
  const auto steps = shell_rows(db, kSteps);
  ASSERT_EQ(std::to_string(steps.size()), answered[0][0]);
  // Per condition: the SD of the PSE ends at the stop rule's 2 mm or the
  // condition used all 40 trials, the entropy falls, and the last estimate
  // lies where `curvlab predict` says the observer's 50 % point is.
  std::map<std::string, std::vector<std::vector<std::string>>> by_track;
  for (const auto& s : steps) by_track[s[0]].push_back(s);
  ASSERT_EQ(by_track.size(), 4u);
  for (const auto& [track, rows] : by_track) {
    SCOPED_TRACE(track);
    const auto& last = rows.back();
    EXPECT_TRUE(std::stod(last[6]) <= 0.002 || rows.size() == 40u) << last[6];
    EXPECT_LT(std::stod(last[8]), std::stod(rows.front()[8]));
    EXPECT_GT(std::stod(last[7]), 0.0);
  }
  const auto skipped = shell_rows(db, "SELECT COUNT(*) FROM trials WHERE status = 'skipped' AND "
                                      "end_reason = 'psi_finished'");
  EXPECT_EQ(std::stoi(skipped[0][0]) + std::stoi(answered[0][0]), 160);

  const auto estimates = shell_rows(
      db, "SELECT json_extract(t.conditions, '$.space') || ' ' || json_extract(t.conditions, '$.projection'), "
          "json_extract(e.detail, '$.pse_mean') FROM events e JOIN trials t ON t.trial_id = e.trial_id "
          "WHERE e.kind = 'posterior' ORDER BY e.event_id");
  std::map<std::string, double> last_estimate;
  for (const auto& e : estimates) last_estimate[e[0]] = std::stod(e[1]);
  const auto predicted = run_shell(std::string(CURVLAB_BIN) + " predict " + kPsi + " --json 2>/dev/null");
  ASSERT_EQ(predicted.exit_code, 0) << predicted.out;
  const auto doc = nlohmann::json::parse(predicted.out);
  ASSERT_EQ(doc["staircases"].size(), 4u) << predicted.out;
  for (const auto& track : doc["staircases"]) {
    const std::string condition = track["space"].get<std::string>() + " " + track["projection"].get<std::string>();
    SCOPED_TRACE(condition);
    EXPECT_EQ(track["rule"], "psi");
    ASSERT_TRUE(track["converges_on"].is_number());
    // Observer noise SD 3.3 mm; the stop rule's posterior SD 2 mm.
    EXPECT_NEAR(last_estimate.at(condition), track["converges_on"].get<double>(), 0.008);
  }
  // The human observer's: a straight stick looks more bowed toward the
  // viewer in H3 than in S3, so H3's PSE is bent further away.
  EXPECT_LT(last_estimate.at("H3 native"), last_estimate.at("S3 native") - 0.02);

  // The export carries the estimates beside the step.
  std::ifstream csv(dir / "export" / "csv" / "trials.csv");
  std::string header;
  std::getline(csv, header);
  for (const char* column : {"pse_mean", "pse_sd", "slope_mean", "slope_sd", "lapse_mean", "posterior_entropy"})
    EXPECT_NE(header.find(std::string(",") + column + ","), std::string::npos) << column << " in " << header;
  std::ifstream description(dir / "export" / "psychds" / "psychds" / "dataset_description.json");
  std::stringstream text;
  text << description.rdbuf();
  EXPECT_NE(text.str().find("\"name\": \"pse_sd\""), std::string::npos);
}

// The operator ends the session half-way (at a fixed time on the session
// clock, which runs the same in both sessions until then); `curvlab resume` replays the stored answers into each condition's
// posterior and goes on: every trial shows what the uninterrupted session
// showed, and every posterior is the same.
TEST(PsiSession, AResumedSessionContinuesWithTheSameValues) {
  const auto dir = fresh_dir("psi_resume");
  const auto whole = (dir / "whole.sqlite").string();
  const auto pieces = (dir / "pieces.sqlite").string();
  auto r = run_cli("run " + kPsi + " --participant P07 --db " + whole + " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;

  // Ended in the inter-trial interval after the 61st trial's answer: that
  // trial is stored complete, and no trial is run again with a new attempt
  // (a repeated attempt draws its own answer, DESIGN.md §6).
  const auto answered = query(whole, "SELECT response_ns FROM trials WHERE trial_index = 60");
  ASSERT_EQ(answered.size(), 1u);
  const double end_s = static_cast<double>(std::stoll(answered[0][0])) * 1e-9 + 0.2;
  const auto script = (dir / "end.txt").string();
  std::ofstream(script) << end_s << " end\n";
  r = run_cli("run " + kPsi + " --participant P07 --db " + pieces + " --render none --quiet --operator-script " +
              script);
  ASSERT_EQ(r.exit_code, 1) << r.out;
  ASSERT_EQ(query(pieces, "SELECT status FROM sessions")[0][0], "interrupted");
  const int before = std::stoi(query(pieces, "SELECT COUNT(*) FROM events WHERE kind = 'posterior'")[0][0]);
  ASSERT_GT(before, 8);   // every condition has answers to replay …
  ASSERT_LT(before, 60);  // … and trials to go
  r = run_cli("resume --db " + pieces + " --session 1 --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(pieces, "SELECT status FROM sessions")[0][0], "completed");

  const auto a = query(whole, kTrials), b = query(pieces, kTrials);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << "trial " << i;
  const auto sa = query(whole, kSteps), sb = query(pieces, kSteps);
  ASSERT_EQ(sa.size(), sb.size());
  ASSERT_FALSE(sa.empty());
  for (std::size_t i = 0; i < sa.size(); ++i) EXPECT_EQ(sa[i], sb[i]) << "step " << i;
}
