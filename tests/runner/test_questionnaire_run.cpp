// Questionnaire blocks run by the real `curvlab`: the SSQ before and after a
// play block answered by the simulated participant, exported and scored,
// the scores read back from questionnaire_scores.csv by a second program
// (python3) that scores the exported answers itself; the same session run
// again gives the same answers; merge pools both; a session killed inside a
// questionnaire resumes at its first unanswered item.
#include "../support/edited_file.hpp"
#include "run_and_kill.hpp"
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_and_kill;
using curvlab::testing::run_cli;
using curvlab::testing::run_shell;

namespace {

using curvlab::test::replaced;

std::string protocol_text() { return curvlab::test::read_text(std::string(CURVLAB_SOURCE_DIR) + "/protocols/ssq_play.toml"); }

// The shipped SSQ protocol with a short play block.
std::string short_protocol() {
  std::string t = protocol_text();
  t = replaced(t, "duration_s = 120", "duration_s = 15");
  t = replaced(t, "shots = 8", "shots = 2");
  return t;
}

std::string write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

// Reads the export with Python's csv module, scores every SSQ block of
// questionnaires.csv with the published weights and compares each with its
// row of questionnaire_scores.csv; prints "ok N" (N SSQ blocks) or the first
// difference.
constexpr const char* kCheckScores = R"PY(
import csv, sys
out = sys.argv[1]
answers = {}
for r in csv.DictReader(open(out + "/questionnaires.csv")):
    if r["instrument"] == "ssq":
        answers.setdefault((r["session_uuid"], r["block"]), {})[int(r["item_index"]) + 1] = int(r["value"])
factors = {"nausea": ([1, 6, 7, 8, 9, 15, 16], 9.54), "oculomotor": ([1, 2, 3, 4, 5, 9, 11], 7.58),
           "disorientation": ([5, 8, 10, 11, 12, 13, 14], 13.92)}
scores = {}
for r in csv.DictReader(open(out + "/questionnaire_scores.csv")):
    if r["instrument"] == "ssq":
        scores[(r["session_uuid"], r["block"], r["subscale"])] = float(r["score"])
for key, v in answers.items():
    if len(v) != 16:
        sys.exit("block %s has %d answers" % (key, len(v)))
    raw = {}
    for name, (items, weight) in factors.items():
        raw[name] = sum(v[i] for i in items)
        want = raw[name] * weight
        if abs(scores[key + (name,)] - want) > 1e-9:
            sys.exit("%s %s: exported %r, scored %r" % (key, name, scores[key + (name,)], want))
    total = (raw["nausea"] + raw["oculomotor"] + raw["disorientation"]) * 3.74
    if abs(scores[key + ("total",)] - total) > 1e-9:
        sys.exit("%s total: exported %r, scored %r" % (key, scores[key + ("total",)], total))
print("ok", len(answers))
)PY";

TEST(QuestionnaireBlock, SsqBeforeAndAfterPlayIsAnsweredStoredScoredAndExported) {
  const auto dir = fresh_dir("questionnaire_run");
  const std::string protocol = write(dir / "p.toml", short_protocol());
  const std::string db = (dir / "p.sqlite").string();
  const auto r = run_cli("run " + protocol + " --participant SIM01 --db " + db + " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  // Two SSQ blocks of 16 items and five presence items, each answered once
  // by the simulated participant, in order, with a time and a label.
  const auto per_block = query(db, "SELECT b.name, x.instrument, count(*), min(x.item_index), max(x.item_index), "
                                   "min(x.rt_ms), group_concat(DISTINCT x.device) FROM questionnaire_answers x "
                                   "JOIN trials t USING (trial_id) JOIN blocks b ON b.block_id = t.block_id "
                                   "GROUP BY b.block_index ORDER BY b.block_index");
  ASSERT_EQ(per_block.size(), 3u);
  EXPECT_EQ(per_block[0][0], "ssq_before");
  EXPECT_EQ(per_block[0][2], "16");
  EXPECT_EQ(per_block[0][3], "0");
  EXPECT_EQ(per_block[0][4], "15");
  EXPECT_EQ(per_block[1][0], "ssq_after");
  EXPECT_EQ(per_block[1][2], "16");
  EXPECT_EQ(per_block[2][1], "presence");
  EXPECT_EQ(per_block[2][2], "5");
  for (const auto& row : per_block) {
    EXPECT_GE(std::stod(row[5]), 700.0) << row[0];  // the simulated reading time
    EXPECT_EQ(row[6], "observer");
  }
  const auto labels = query(db, "SELECT DISTINCT value, label FROM questionnaire_answers WHERE instrument = 'ssq' "
                                "ORDER BY value");
  for (const auto& l : labels)
    EXPECT_EQ(l[1], std::vector<std::string>({"None", "Slight", "Moderate", "Severe"})[std::stoul(l[0])]);
  // Each block's subscales stored when it ended: four for each SSQ, two for presence.
  const auto scores = query(db, "SELECT instrument, count(*), sum(score IS NULL) FROM questionnaire_scores "
                                "GROUP BY instrument ORDER BY instrument");
  ASSERT_EQ(scores.size(), 2u);
  EXPECT_EQ(scores[0], (std::vector<std::string>{"presence", "2", "0"}));
  EXPECT_EQ(scores[1], (std::vector<std::string>{"ssq", "8", "0"}));
  // Start and end events, and the blocks' trials completed.
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'questionnaire_start'")[0][0], "3");
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'questionnaire_end'")[0][0], "3");
  EXPECT_EQ(query(db, "SELECT count(*) FROM trials WHERE status != 'completed'")[0][0], "0");

  const auto out = (dir / "export").string();
  const auto e = run_cli("export --db " + db + " --out " + out + " --format all");
  ASSERT_EQ(e.exit_code, 0) << e.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "export" / "questionnaires.csv"));
  EXPECT_TRUE(std::filesystem::exists(dir / "export" / "questionnaire_scores.csv"));
  EXPECT_TRUE(std::filesystem::exists(
      dir / "export" / "psychds" / "data" / "study-ssqplay_subject-SIM01_session-1_task-questionnaire_data.csv"));
  write(dir / "check.py", kCheckScores);
  const auto checked = run_shell("/usr/bin/python3 " + (dir / "check.py").string() + " " + out + " 2>&1");
  EXPECT_EQ(checked.exit_code, 0) << checked.out;
  EXPECT_EQ(checked.out, "ok 2\n");

  // The same participant run again answers the same: the answers come from
  // the session's seed alone.
  const std::string again = (dir / "again.sqlite").string();
  ASSERT_EQ(run_cli("run " + protocol + " --participant SIM01 --db " + again + " --render none --quiet").exit_code, 0);
  const std::string values = "SELECT group_concat(value, ',') FROM (SELECT value FROM questionnaire_answers "
                             "ORDER BY trial_id, item_index)";
  EXPECT_EQ(query(again, values), query(db, values));

  // merge pools both sessions' answers and scores, with their trials, once
  // however often it runs; a pooled export gives the merged file's tables.
  const std::string study = (dir / "study.sqlite").string();
  for (int pass = 0; pass < 2; ++pass) {
    const auto m = run_cli("merge --out " + study + " " + db + " " + again);
    ASSERT_EQ(m.exit_code, 0) << m.out;
  }
  EXPECT_EQ(query(study, "SELECT count(*) FROM questionnaire_answers")[0][0], "74");
  EXPECT_EQ(query(study, "SELECT count(*) FROM questionnaire_scores WHERE score IS NOT NULL")[0][0], "20");
  EXPECT_EQ(query(study, "SELECT count(*) FROM questionnaire_answers x JOIN trials t USING (trial_id) "
                         "WHERE t.session_id != x.session_id")[0][0],
            "0");
  const auto from_study = run_cli("export --db " + study + " --out " + (dir / "study_export").string() + " --format csv");
  ASSERT_EQ(from_study.exit_code, 0) << from_study.out;
  const auto pooled = run_cli("export --db " + db + " " + again + " --out " + (dir / "pooled_export").string() +
                              " --format csv");
  ASSERT_EQ(pooled.exit_code, 0) << pooled.out;
  for (const char* file : {"questionnaires.csv", "questionnaire_scores.csv"}) {
    std::ifstream a(dir / "study_export" / file), b(dir / "pooled_export" / file);
    std::stringstream sa, sb;
    sa << a.rdbuf();
    sb << b.rdbuf();
    EXPECT_FALSE(sa.str().empty()) << file;
    EXPECT_EQ(sa.str(), sb.str()) << file;
  }
}

TEST(QuestionnaireBlock, KilledMidQuestionnaireResumesAtTheFirstUnansweredItem) {
  const auto dir = fresh_dir("questionnaire_kill");
  const std::string protocol = write(dir / "p.toml", short_protocol());
  const std::string db = (dir / "p.sqlite").string();
  const auto answered = [&] {
    if (!std::filesystem::exists(db)) return 0;
    const auto rows = query(db, "SELECT count(*) FROM questionnaire_answers");
    return rows.empty() ? 0 : std::stoi(rows[0][0]);
  };
  ASSERT_TRUE(run_and_kill({"run", protocol, "--participant", "SIM01", "--db", db, "--render", "none", "--pace",
                            "realtime"},
                           std::chrono::milliseconds(0), [&] { return answered() >= 3; }))
      << "the session ended before three items were answered";
  const auto kept = query(db, "SELECT item_index, value, t_ns FROM questionnaire_answers ORDER BY item_index");
  ASSERT_GE(kept.size(), 3u);
  ASSERT_LT(kept.size(), 16u);
  const auto r = run_cli("resume --db " + db + " --session 1 --render none --pace fast --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
  // The resumed run started at the first item not stored, and nothing
  // stored before the kill changed.
  const auto starts = query(db, "SELECT json_extract(detail, '$.first_item') FROM events "
                                "WHERE kind = 'questionnaire_start' ORDER BY event_id");
  ASSERT_GE(starts.size(), 2u);
  EXPECT_EQ(starts[0][0], "0");
  EXPECT_EQ(starts[1][0], std::to_string(kept.size()));
  const auto all = query(db, "SELECT item_index, value, t_ns FROM questionnaire_answers x JOIN trials t "
                             "USING (trial_id) WHERE t.trial_index = 0 ORDER BY item_index");
  ASSERT_EQ(all.size(), 16u);
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(all[i], kept[i]);
  // And the answers are those of an uninterrupted session.
  const std::string whole = (dir / "whole.sqlite").string();
  ASSERT_EQ(run_cli("run " + protocol + " --participant SIM01 --db " + whole + " --render none --quiet").exit_code, 0);
  const std::string values = "SELECT group_concat(value, ',') FROM (SELECT value FROM questionnaire_answers "
                             "ORDER BY trial_id, item_index)";
  EXPECT_EQ(query(db, values), query(whole, values));
}

}  // namespace
