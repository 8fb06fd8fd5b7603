// Play blocks run by the real `curvlab`: judge → play → judge with the
// simulated player in S3, E3 and H3; every stored shot, handed to a second
// program (`curvlab billiards shot`) from its stored inputs alone, gives the
// stored events; a play block killed with SIGKILL resumes at the rest state
// after its last completed shot.
#include "../support/edited_file.hpp"
#include "run_and_kill.hpp"
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_and_kill;
using curvlab::testing::run_cli;
using Json = nlohmann::ordered_json;

namespace {

using curvlab::test::replaced;

std::string protocol_text() { return curvlab::test::read_text(std::string(CURVLAB_SOURCE_DIR) + "/protocols/adaptation_play.toml"); }

// The adaptation protocol with its play block in `space`.
std::string play_in(const std::string& space) {
  std::string t = protocol_text();
  t = replaced(t, "levels = [\"E3\", \"H3\"]", "levels = [\"S3\", \"E3\", \"H3\"]");
  t = replaced(t, "levels = { space = \"H3\" }", "levels = { space = \"" + space + "\" }");
  return t;
}

std::string write(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path) << text;
  return path.string();
}

TEST(PlayBlock, JudgePlayJudgeRunsInEverySpaceAndEachStoredShotReplaysToItsEvents) {
  for (const std::string space : {"S3", "E3", "H3"}) {
    SCOPED_TRACE(space);
    const auto dir = fresh_dir("play_" + space);
    const std::string protocol = write(dir / "p.toml", play_in(space));
    const std::string db = (dir / "p.sqlite").string();
    const auto r = run_cli("run " + protocol + " --participant SIM01 --db " + db + " --render none --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const Json summary = Json::parse(r.out.substr(r.out.find('{')));
    EXPECT_EQ(summary["status"], "completed");
    EXPECT_GT(summary["shots"].get<int>(), 0);
    // Laps round the physical table per lap round the virtual one: n/4,
    // from the head's positions (the paper's 0.75, 1 and 1.25).
    const double sides = space == "S3" ? 3.0 : space == "E3" ? 4.0 : 5.0;
    ASSERT_EQ(summary["play"].size(), 1u);
    EXPECT_GT(std::abs(summary["play"][0]["laps_physical"].get<double>()), 2.0);
    EXPECT_NEAR(summary["play"][0]["laps_ratio"].get<double>(), sides / 4.0, 0.01);
    EXPECT_LT(summary["play"][0]["hand_error_m"].get<double>(), 1e-6);
    const auto summaries = query(db, "SELECT json_extract(detail, '$.laps_physical') FROM events WHERE kind = 'play_summary'");
    ASSERT_EQ(summaries.size(), 1u);
    const auto shots = query(db, "SELECT shot_index, table_settings, before_state, shot, events, rest_state, "
                                 "event_count FROM shots ORDER BY shot_index");
    ASSERT_EQ(static_cast<int>(shots.size()), summary["shots"].get<int>());
    std::string previous_rest;
    for (const auto& row : shots) {
      SCOPED_TRACE("shot " + row[0]);
      const Json settings = Json::parse(row[1]);
      EXPECT_EQ(settings["space"], space);
      // The shot's start is the previous shot's rest state.
      if (!previous_rest.empty()) {
        EXPECT_EQ(Json::parse(row[2])["balls"], Json::parse(previous_rest));
      }
      previous_rest = row[5];
      Json state = Json::parse(row[2]);
      state["shot"] = Json::parse(row[3]);
      const std::string file = write(dir / ("shot" + row[0] + ".json"), state.dump());
      std::string sets;
      for (const auto& [name, value] : settings["parameters"].items()) {
        std::ostringstream v;
        v.precision(17);
        v << value.get<double>();
        sets += " --set " + name + "=" + v.str();
      }
      const auto again = run_cli("billiards shot --json --space " + space + " --edge-m " +
                                 std::to_string(settings["edge_m"].get<double>()) + " --state " + file + sets);
      ASSERT_EQ(again.exit_code, 0) << again.out;
      const Json out = Json::parse(again.out);
      EXPECT_EQ(out["events"], Json::parse(row[4]));
      EXPECT_EQ(static_cast<long>(out["events"].size()), std::stol(row[6]));
      Json rest = Json::array();
      for (const auto& b : out["final"]) {
        Json place{{"id", b["id"]}, {"x_m", b["x_m"]}, {"z_m", b["z_m"]}};
        if (b["pocketed"].get<bool>()) {
          place["pocketed"] = true;
          place["pocket"] = b["pocket"];
        }
        rest.push_back(place);
      }
      // A pocketed cue ball is stored back on the table (respotted).
      Json stored = Json::parse(row[5]);
      if (rest[0].value("pocketed", false)) {
        EXPECT_FALSE(stored[0].value("pocketed", false));
        rest.erase(0);
        stored.erase(0);
      }
      EXPECT_EQ(rest, stored);
    }
    // The play block is one completed trial between the judgement blocks.
    const auto trials = query(db, "SELECT count(*) FROM trials WHERE status != 'completed'");
    EXPECT_EQ(trials[0][0], "0");
  }
}


TEST(PlayBlock, KilledMidPlayResumesAtTheRestStateAfterTheLastShot) {
  const auto dir = fresh_dir("play_kill");
  // One judgement each side of a realtime play block of a few shots.
  std::string t = protocol_text();
  t = replaced(t, "repetitions = 2", "repetitions = 1");
  t = replaced(t, "name = \"before\"", "name = \"before\"\nlevels = { space = \"E3\", bend = 0.0 }");
  t = replaced(t, "name = \"after\"", "name = \"after\"\nlevels = { space = \"E3\", bend = 0.0 }");
  t = replaced(t, "shots = 8", "shots = 4");
  const std::string protocol = write(dir / "p.toml", t);
  const std::string db = (dir / "p.sqlite").string();
  const auto shots_stored = [&] {
    if (!std::filesystem::exists(db)) return 0;
    const auto rows = query(db, "SELECT count(*) FROM shots");
    return rows.empty() ? 0 : std::stoi(rows[0][0]);
  };
  ASSERT_TRUE(run_and_kill({"run", protocol, "--participant", "SIM01", "--db", db, "--render", "none",
                                   "--pace", "realtime"},
                           std::chrono::milliseconds(0), [&] { return shots_stored() >= 2; }))
      << "the session ended before two shots were stored";
  const int before = shots_stored();
  ASSERT_GE(before, 2);
  ASSERT_LT(before, 4);
  const auto kept = query(db, "SELECT shot_index, events, rest_state FROM shots ORDER BY shot_index");
  const auto r = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto status = query(db, "SELECT status FROM sessions");
  EXPECT_EQ(status[0][0], "completed");
  const auto shots = query(db, "SELECT shot_index, events, rest_state, before_state FROM shots ORDER BY shot_index");
  ASSERT_EQ(shots.size(), 4u);
  for (std::size_t i = 0; i < shots.size(); ++i) EXPECT_EQ(shots[i][0], std::to_string(i));
  // Nothing committed was lost or changed, and play went on from the rest
  // state of the last shot stored before the kill.
  for (std::size_t i = 0; i < kept.size(); ++i) {
    EXPECT_EQ(shots[i][1], kept[i][1]);
    EXPECT_EQ(shots[i][2], kept[i][2]);
  }
  EXPECT_EQ(Json::parse(shots[kept.size()][3])["balls"], Json::parse(kept.back()[2]));
}

}  // namespace

namespace {

TEST(PlayBlock, ReplayDrawsAFrameOfPlayFromTheStoredShots) {
  const auto dir = fresh_dir("play_replay");
  const std::string db = (dir / "p.sqlite").string();
  ASSERT_EQ(run_cli("run " + write(dir / "p.toml", protocol_text()) + " --participant SIM01 --db " + db +
                    " --render none --quiet").exit_code, 0);
  const auto play = query(db, "SELECT trial_index, trial_id FROM trials t JOIN blocks b USING (block_id) "
                              "WHERE b.name = 'play'");
  ASSERT_EQ(play.size(), 1u);
  const auto shot = query(db, "SELECT t_ns FROM shots WHERE shot_index = 0");
  const auto frame = query(db, "SELECT frame_index FROM frames WHERE trial_id = " + play[0][1] +
                                   " AND predicted_display_ns > " + shot[0][0] + " + 100000000 LIMIT 1");
  ASSERT_EQ(frame.size(), 1u);
  const auto r = run_cli("replay --db " + db + " --session 1 --trial " + play[0][0] + " --frame " + frame[0][0] +
                         " --out " + (dir / "frame").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "frame" / "left.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "frame" / "right.png"));
  // A play block has no onset: the frame must be named.
  const auto no_frame = run_cli("replay --db " + db + " --session 1 --trial " + play[0][0] + " --out " +
                                (dir / "none").string());
  EXPECT_EQ(no_frame.exit_code, 2);
  EXPECT_NE(no_frame.out.find("--frame"), std::string::npos) << no_frame.out;
}

}  // namespace

// `predict` forecasts the judgements before and after play, not the play
// block's one trial: the trials it counts are the design's outside that block.
TEST(PlayBlock, PredictCountsOnlyTheJudgementTrials) {
  const std::string file = std::string(CURVLAB_SOURCE_DIR) + "/protocols/adaptation_play.toml";
  const auto design = run_cli("design " + file + " --participant 1 --json");
  ASSERT_EQ(design.exit_code, 0) << design.out;
  const Json trials = Json::parse(design.out)["trials"];
  int judged = 0;
  for (const auto& t : trials) judged += t["block"] != "play" ? 1 : 0;
  const auto predicted = run_cli("predict " + file + " --participants 4 --simulations 20 --json");
  ASSERT_EQ(predicted.exit_code, 0) << predicted.out;
  const Json j = Json::parse(predicted.out.substr(predicted.out.find('{')));
  int counted = 0;
  for (const auto& c : j["conditions"]) counted += c["trials_per_participant"].get<int>();
  EXPECT_EQ(counted, judged);
  EXPECT_NE(j["notes"].dump().find("play and questionnaire blocks are not predicted"), std::string::npos) << j["notes"];
}

// `preview` shows the judged blocks' conditions and describes the play
// block in the block table: the play block's one trial is no condition.
TEST(PlayBlock, PreviewDescribesThePlayBlockAndShowsNoConditionForIt) {
  const std::string file = std::string(CURVLAB_SOURCE_DIR) + "/protocols/adaptation_play.toml";
  const auto dir = std::filesystem::temp_directory_path() / ("curvlab_play_preview_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const auto r = run_cli("preview " + file + " --out " + dir.string() + " --size 64x64 --software");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string html = curvlab::test::read_text((dir / "index.html").string());
  EXPECT_NE(html.find("play: billiards until 1 min"), std::string::npos) << "the block table does not describe play";
  // Each condition panel lists its trials per block; none names the play block.
  for (std::size_t at = html.find("<th>trials per block</th><td>"); at != std::string::npos;
       at = html.find("<th>trials per block</th><td>", at + 1)) {
    const std::string cell = html.substr(at, html.find("</td>", at) - at);
    EXPECT_EQ(cell.find("play:"), std::string::npos) << cell;
  }
  EXPECT_EQ(html.find("prompt in block play"), std::string::npos);
  std::filesystem::remove_all(dir);
}
