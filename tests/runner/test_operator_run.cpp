// Scripted operator actions in whole headless sessions through the program
// (the simulated clock of a fast run makes them land at the same frames on
// every run), and the --progress json stream.
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;

namespace {

const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

std::string write_script(const std::filesystem::path& dir, const std::string& text) {
  const auto path = dir / "ops.txt";
  std::ofstream(path) << text;
  return path.string();
}

}  // namespace

// A note, a pause mid-trial with its resume, a skip: the data say what the
// operator did, and the session still completes.
TEST(OperatorRun, NotePauseAndSkipLandInTheData) {
  const auto dir = fresh_dir("operator_run");
  const auto db = (dir / "s.sqlite").string();
  const std::string note = "  P01 rubbed their eyes; \"#2\" may be off ";
  const auto ops = write_script(dir, "# operator\n0.25 pause\n0.5 resume\n0.6 note" + note + "\n3.3 skip\n");
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " + db + " --render none --quiet --json " +
                         "--operator-script " + ops);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(doc["status"], "completed");
  EXPECT_EQ(doc["trials_skipped"], 1);
  EXPECT_EQ(doc["trials_completed"], 7);

  const auto skipped = query(db, "SELECT trial_id, end_reason FROM trials WHERE status = 'skipped'");
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0][1], "operator");
  const auto note_rows = query(db, "SELECT json_extract(detail, '$.text'), t_ns FROM events WHERE kind = 'operator_note'");
  ASSERT_EQ(note_rows.size(), 1u);
  EXPECT_EQ(note_rows[0][0], note.substr(1));  // verbatim after the one blank that ends "note"
  // On the session clock, at the script's time (0.6 s) within one frame.
  const auto start = query(db, "SELECT MIN(t_ns) FROM frames")[0][0];
  const double at_s = static_cast<double>(std::stoll(note_rows[0][1]) - std::stoll(start)) * 1e-9;
  EXPECT_NEAR(at_s, 0.6, 0.03);
  // The pause fell in the first trial's attempt: aborted, run again.
  const auto repeated = query(db, "SELECT trial_id FROM events WHERE kind = 'trial_repeated' AND "
                                  "json_extract(detail, '$.reason') = 'pause'");
  ASSERT_EQ(repeated.size(), 1u);
  EXPECT_EQ(query(db, "SELECT attempt, status FROM trials WHERE trial_id = " + repeated[0][0])[0],
            (std::vector<std::string>{"2", "completed"}));
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM events WHERE kind = 'operator_action'")[0][0], "3");
}

// `end` leaves the session resumable, and the resume never runs the skipped trial.
TEST(OperatorRun, EndLeavesTheSessionResumableAndASkipStaysSkipped) {
  const auto dir = fresh_dir("operator_end");
  const auto db = (dir / "s.sqlite").string();
  const auto ops = write_script(dir, "0.2 skip\n2.0 end\n");
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " + db + " --render none --quiet --json " +
                         "--operator-script " + ops);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("curvlab resume"), std::string::npos) << r.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "interrupted");
  const auto skipped_id = query(db, "SELECT trial_id FROM trials WHERE status = 'skipped'")[0][0];
  const auto resumed = run_cli("resume --db " + db + " --session 1 --render none --quiet --json");
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  EXPECT_EQ(query(db, "SELECT status, end_reason, attempt FROM trials WHERE trial_id = " + skipped_id)[0],
            (std::vector<std::string>{"skipped", "operator", "1"}));
  EXPECT_EQ(query(db, "SELECT COUNT(*) FROM trials WHERE status = 'completed'")[0][0], "7");
}

TEST(OperatorRun, ABadScriptLineIsNamedBeforeAnythingRuns) {
  const auto dir = fresh_dir("operator_bad");
  const auto db = dir / "s.sqlite";
  const auto ops = write_script(dir, "1 pause\n\n2.5 skip please\n");
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " + db.string() + " --operator-script " + ops);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(ops + ":3: 'skip' takes no text"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

// One JSON object per trial on stdout, then the summary.
TEST(OperatorRun, ProgressJsonIsALinePerTrial) {
  const auto dir = fresh_dir("operator_progress");
  const auto db = (dir / "s.sqlite").string();
  const auto r = run_cli("run " + kDemo + " --participant P01 --db " + db + " --render none --progress json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::istringstream lines(r.out);
  std::string line;
  int trials = 0;
  while (std::getline(lines, line)) {
    if (line.empty() || line.front() != '{' || line.back() != '}') continue;
    const auto j = nlohmann::json::parse(line);
    ++trials;
    EXPECT_EQ(j["trial"], trials);
    EXPECT_EQ(j["of"], 8);
    EXPECT_EQ(j["status"], "completed");
    EXPECT_TRUE(j["conditions"].contains("space"));
    EXPECT_TRUE(j.contains("response"));
    EXPECT_TRUE(j.contains("frames_late"));
  }
  EXPECT_EQ(trials, 8);
}
