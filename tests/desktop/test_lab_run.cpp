// `curvlab run` with the lab backends, as an experimenter runs it: a desktop
// pilot of the demo protocol on Xvfb answered by a key script, and the xr
// backend on a machine without an OpenXR runtime.
#include "../cli/run_cli.hpp"
#include "xvfb.hpp"
#include "../support/edited_file.hpp"
#include "../support/png_files.hpp"
#include "../support/table_protocol.hpp"

#include "curvlab/renderer/image_io.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

namespace {

using curvlab::testing::run_cli;

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("curvlab_lab_run_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

int count_trials(const std::string& db_path, const std::string& status) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(db);
    return -1;
  }
  sqlite3_stmt* stmt = nullptr;
  int n = -1;
  if (sqlite3_prepare_v2(db, "SELECT count(*) FROM trials WHERE status = ?", -1, &stmt, nullptr) ==
      SQLITE_OK) {
    sqlite3_bind_text(stmt, 1, status.c_str(), -1, SQLITE_TRANSIENT);
    if (sqlite3_step(stmt) == SQLITE_ROW) n = sqlite3_column_int(stmt, 0);
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return n;
}

// A key script saved in Latin-1 is refused before a window opens or a
// session is written: exit 2 naming its line and byte.
TEST(LabRun, AKeyScriptThatIsNotUtf8IsRefusedBeforeTheSession) {
  const auto dir = fresh_dir("latin1_keys");
  std::ofstream(dir / "keys.txt", std::ios::binary) << "# Ren\xE9's pilot\nspace 100\n";
  const auto db = dir / "pilot.db";
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/demo.toml --participant T1 --db " +
                         db.string() + " --backend desktop --software --window-size 256x256 --key-script " +
                         (dir / "keys.txt").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find((dir / "keys.txt").string() +
                       ":1: the key script is not UTF-8 (byte 0xE9 at column 6); save the file as UTF-8"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
}

TEST(LabRun, DesktopPilotOfTheDemoCompletesWithScriptedKeys) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  const auto dir = fresh_dir("desktop");
  // Any instruction page first, then one answer per trial; a key the runner
  // does not expect is ignored and the next one follows.
  std::ofstream keys(dir / "keys.txt");
  keys << "# demo: 8 trials answered 'straight'\nspace 100\n";
  for (int i = 0; i < 8; ++i) keys << "2 100\n";
  keys << "space 100\nspace 100\n";
  keys.close();
  const auto db = dir / "pilot.db";
  const auto shots = dir / "shots";
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/demo.toml --participant T1 --db " +
                         db.string() + " --backend desktop --software --window-size 256x256 --key-script " +
                         (dir / "keys.txt").string() + " --screenshot " + shots.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto json_start = r.out.find('{');
  ASSERT_NE(json_start, std::string::npos) << r.out;
  const auto doc = nlohmann::json::parse(r.out.substr(json_start));
  EXPECT_EQ(doc["status"], "completed");
  EXPECT_EQ(doc["trials_planned"], 8);
  EXPECT_EQ(doc["trials_completed"], 8);
  EXPECT_EQ(count_trials(db.string(), "completed"), 8);

  // One onset screenshot per trial, each showing the table's cloth.
  for (int trial = 1; trial <= 8; ++trial) {
    char name[40];
    std::snprintf(name, sizeof name, "stimulus_%03d_left.png", trial);
    curvlab::renderer::Rgba8Image img;
    ASSERT_TRUE(curvlab::test::read_png_into((shots / name).string(), img));
    ASSERT_EQ(img.width, 256);
    int cloth = 0;
    int distinct_from_first = 0;
    for (std::size_t i = 0; i + 3 < img.pixels.size(); i += 4) {
      const int rr = img.pixels[i], g = img.pixels[i + 1], b = img.pixels[i + 2];
      if (g > 40 && g > rr + 25 && g > b + 15) ++cloth;
      if (img.pixels[i] != img.pixels[0] || img.pixels[i + 1] != img.pixels[1]) ++distinct_from_first;
    }
    EXPECT_GT(distinct_from_first, 256 * 256 / 10) << name << " is blank";
    EXPECT_GT(cloth, 256 * 256 / 20) << name << " shows no table cloth";
  }
  std::filesystem::remove_all(dir);
}

// Replay redraws a desktop session's onset frames from the recorded eye
// geometry — the window's eye size and field of view, not the protocol's
// resolution and the headless 90° — pixel for pixel as the window showed them.
TEST(LabRun, ReplayReproducesTheDesktopOnsetFrame) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  const auto dir = fresh_dir("desktop_replay");
  std::ofstream keys(dir / "keys.txt");
  keys << "space 100\n";
  for (int i = 0; i < 8; ++i) keys << "2 100\n";
  keys << "space 100\nspace 100\n";
  keys.close();
  const auto db = (dir / "pilot.db").string();
  const auto shots = dir / "shots";
  // A window eye that is neither square nor the protocol's resolution.
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/demo.toml --participant T2 --db " +
                         db + " --backend desktop --software --window-size 240x160 --key-script " +
                         (dir / "keys.txt").string() + " --screenshot " + shots.string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  for (int trial : {0, 5}) {
    const auto out = dir / ("replay" + std::to_string(trial));
    const auto rp = run_cli("replay --db " + db + " --session 1 --trial " + std::to_string(trial) + " --out " +
                            out.string() + " --software");
    ASSERT_EQ(rp.exit_code, 0) << rp.out;
    std::ifstream json(out / "replay.json");
    const auto doc = nlohmann::json::parse(json);
    EXPECT_EQ(doc["eye_geometry"], "recorded");
    for (const char* eye : {"left", "right"}) {
      char name[48];
      std::snprintf(name, sizeof name, "stimulus_%03d_%s.png", trial + 1, eye);
      curvlab::renderer::Rgba8Image shown, replayed;
      ASSERT_TRUE(curvlab::test::read_png_into((shots / name).string(), shown));
      ASSERT_TRUE(curvlab::test::read_png_into((out / (std::string(eye) + ".png")).string(), replayed));
      EXPECT_EQ(replayed.width, 240);
      EXPECT_EQ(replayed.height, 160);
      const auto diff = curvlab::renderer::diff_images(shown, replayed, 0);
      EXPECT_EQ(diff.differing_pixels, 0) << name << ": largest channel difference " << diff.max_channel_diff;
    }
  }
  std::filesystem::remove_all(dir);
}

// The key-script example of docs/lab.md, "Key scripts", as the docs show it.
std::string docs_key_script() {
  std::ifstream in(std::string(CURVLAB_SOURCE_DIR) + "/docs/lab.md");
  std::stringstream text;
  text << in.rdbuf();
  const std::string doc = text.str();
  const auto section = doc.find("### Key scripts");
  if (section == std::string::npos) return {};
  const auto open = doc.find("```\n", section);
  const auto close = doc.find("```", open + 4);
  if (open == std::string::npos || close == std::string::npos) return {};
  return doc.substr(open + 4, close - open - 4);
}

// A single value of a query on a database file, as text ("" when none).
std::string query_text(const std::string& db_path, const std::string& sql) {
  sqlite3* db = nullptr;
  std::string value;
  if (sqlite3_open_v2(db_path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr) == SQLITE_OK && sqlite3_step(stmt) == SQLITE_ROW &&
        sqlite3_column_text(stmt, 0) != nullptr)
      value = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    sqlite3_finalize(stmt);
  }
  sqlite3_close(db);
  return value;
}

// The docs' example pilots the whole proposed study (168 trials, breaks that
// must stay up 10 s, a 500 ms fixation before every stimulus): every trial
// answered by the script, none of its keys dropped as early. Headless in
// simulated time, so the 13-minute session takes seconds.
TEST(LabRun, TheDocsKeyScriptPilotsTheWholeProposedStudy) {
  const auto dir = fresh_dir("docs_script");
  const std::string script = docs_key_script();
  ASSERT_NE(script.find("response+150"), std::string::npos) << "docs/lab.md's key script example not found:\n"
                                                             << script;
  std::ofstream(dir / "keys.txt") << script;
  const auto db = dir / "pilot.db";
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/proposed_study.toml --participant PILOT1 "
                         "--db " + db.string() + " --render none --key-script " + (dir / "keys.txt").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(doc["status"], "completed");
  EXPECT_EQ(doc["trials_planned"], 168);
  EXPECT_EQ(doc["trials_completed"], 168);
  EXPECT_EQ(query_text(db.string(), "SELECT count(*) FROM trials WHERE response = 'straight' AND "
                                    "response_device = 'script'"),
            "168");
  EXPECT_EQ(query_text(db.string(), "SELECT count(*) FROM events WHERE kind = 'early_input'"), "0");
  std::filesystem::remove_all(dir);
}

// A line that would land in the wrong phase is refused at load with its file
// and line, before anything is written.
TEST(LabRun, AKeyScriptLineInTheWrongPhaseIsRefusedWithFileAndLine) {
  const auto dir = fresh_dir("wrong_phase");
  std::ofstream(dir / "keys.txt") << "space instructions+300 repeat\n2 response+150\n2 response+4000\n";
  const auto db = dir / "pilot.db";
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/proposed_study.toml --participant PILOT1 "
                         "--db " + db.string() + " --render none --key-script " + (dir / "keys.txt").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find((dir / "keys.txt").string() +
                       ":3: '2 response+4000' would land in the iti, not the response (it lasts 4000 ms in "),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(std::filesystem::exists(db));
  std::filesystem::remove_all(dir);
}

// A script that stops answering ends the session with a message at the first
// page left waiting, resumable, instead of waiting forever; a scripted
// Escape ends it as the key does.
TEST(LabRun, AKeyScriptThatStopsOrEscapesEndsTheSessionResumable) {
  const auto dir = fresh_dir("ran_out");
  std::ofstream(dir / "short.txt") << "space instructions\nspace instructions\nspace instructions\n";
  const auto db = dir / "pilot.db";
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/proposed_study.toml --participant PILOT1 "
                         "--db " + db.string() + " --render none --key-script " + (dir / "short.txt").string());
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("the key script " + (dir / "short.txt").string() +
                       " ran out (its last key, line 3, was pressed) and the instructions page waited 5 s for a key"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("curvlab resume --db " + db.string() + " --session 1"), std::string::npos) << r.out;
  EXPECT_EQ(query_text(db.string(), "SELECT status FROM sessions WHERE session_id = 1"), "interrupted");

  std::ofstream(dir / "escape.txt") << "space instructions+300 repeat\n2 response+150\nescape response+100\n";
  const auto r2 = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/proposed_study.toml --participant "
                          "PILOT2 --db " + db.string() + " --render none --key-script " + (dir / "escape.txt").string());
  EXPECT_EQ(r2.exit_code, 1) << r2.out;
  EXPECT_NE(r2.out.find("curvlab resume --db " + db.string() + " --session 2"), std::string::npos) << r2.out;
  EXPECT_EQ(query_text(db.string(), "SELECT status FROM sessions WHERE session_id = 2"), "interrupted");
  EXPECT_EQ(query_text(db.string(), "SELECT count(*) FROM trials WHERE session_id = 2 AND status = 'completed'"), "1");
  std::filesystem::remove_all(dir);
}

TEST(LabRun, XrWithoutARuntimeExitsWithTheResultAndWritesNothing) {
  const auto dir = fresh_dir("xr");
  const auto db = dir / "s.db";
  // A protocol the controllers can answer (demo.toml binds keys only and is refused first).
  const auto r = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/proposed_study.toml --participant P1 --db " +
                         db.string() + " --backend xr");
  if (r.exit_code == 0) GTEST_SKIP() << "an OpenXR runtime and headset are present";
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("XR_ERROR_RUNTIME_UNAVAILABLE (-51)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Monado"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("SteamVR"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "something was written: the database?";
  std::filesystem::remove_all(dir);
}

}  // namespace

namespace {

// A desktop pilot of a play block: the key script swings the right hand (the
// cue's tip) through the cue ball, and the strike is read from the tip's
// motion: one shot by the participant, along the swing, at its speed.
TEST(LabRun, ADesktopPilotStrikesTheCueBallWithTheTrackedCue) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  const auto dir = fresh_dir("play_cue");
  std::ofstream(dir / "play.toml") << curvlab::test::table_protocol_head("play-pilot") +
                                          "[[blocks]]\nname = \"play\"\nkind = \"play\"\nduration_s = 8\nshots = 1\n"
                                          "instructions = [\"Play.\"]\n";
  // The cue ball rests 0.2 m in from the middle of edge 0, at cue height;
  // the hand moves 0.25 m toward the centre in four 20 ms steps.
  std::ofstream(dir / "keys.txt") << "space 300\nhand right 0 0.79 0.45 300\nhand right 0 0.79 0.33 20\n"
                                     "hand right 0 0.79 0.27 20\nhand right 0 0.79 0.23 20\nhand right 0 0.79 0.20 20\n"
                                     // The closing page: a person would press space; the script does.
                                     "space done+300\n";
  const auto db = (dir / "pilot.db").string();
  const auto r = run_cli("run " + (dir / "play.toml").string() + " --participant T3 --db " + db +
                         " --backend desktop --software --window-size 256x256 --key-script " +
                         (dir / "keys.txt").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  sqlite3* handle = nullptr;
  ASSERT_EQ(sqlite3_open_v2(db.c_str(), &handle, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(handle, "SELECT player, cue_speed_m_s, aim_x, aim_z, event_count, cue_pose FROM shots",
                               -1, &stmt, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0))), "participant");
  EXPECT_GT(sqlite3_column_double(stmt, 1), 0.3);
  EXPECT_LT(sqlite3_column_double(stmt, 1), 6.0);
  EXPECT_NEAR(sqlite3_column_double(stmt, 2), 0.0, 0.05);
  EXPECT_NEAR(sqlite3_column_double(stmt, 3), -1.0, 0.01);
  EXPECT_GT(sqlite3_column_int(stmt, 4), 0);
  EXPECT_NE(sqlite3_column_type(stmt, 5), SQLITE_NULL);
  EXPECT_EQ(sqlite3_step(stmt), SQLITE_DONE);
  sqlite3_finalize(stmt);
  sqlite3_close(handle);
}

}  // namespace

// The start form, filled in by a person who reads only the window (keys
// typed through the X server by xdotool): a pseudonym already in the data
// file asks for Enter again, then the session runs as `curvlab run` would
// with --new-session and the note stored with its start; Escape closes the
// form and starts nothing.
TEST(LabRun, DesktopStartFormStartsTheSessionItDescribes) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  if (std::system("command -v xdotool > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "xdotool is not installed (apt-get install xdotool)";
  const auto dir = fresh_dir("start_form");
  std::filesystem::create_directories(dir / "protocols");
  // One short trial: the demo with one level of each factor.
  std::ofstream(dir / "protocols" / "a_short.toml") << curvlab::test::edited_file(
      std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml",
      {{"levels = [\"E3\", \"H3\"]", "levels = [\"H3\"]"},
       {"levels = [\"tourist\", \"native\"]", "levels = [\"native\"]"},
       {"repetitions = 2", "repetitions = 1"}});
  std::filesystem::copy_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml", dir / "protocols" / "demo.toml");
  const auto db = (dir / "lab.sqlite").string();
  ASSERT_EQ(run_cli("run " + (dir / "protocols" / "a_short.toml").string() + " --participant P01 --db " + db +
                    " --render none --quiet")
                .exit_code,
            0);

  // The form in a window; the keys a person would press, reading it.
  auto fill = [&](const std::string& keys) {
    return curvlab::testing::run_shell(
        "cd " + dir.string() + " && (" + CURVLAB_BIN + " start --db " + db +
        " --protocols protocols --software --window-size 320x320 > form.out 2>&1 & pid=$!; "
        "timeout 60 xdotool search --sync --name '^curvlab' windowfocus --sync > /dev/null && "
        "xdotool key --delay 60 " + keys + "; wait $pid; echo \"exit $?\" >> form.out); cat form.out");
  };
  // P01 (shift+p 0 1), Tab to the protocol (the first, a_short), Tab to the
  // backend, Right Right (desktop → xr → headless), Tab to the note.
  auto r = fill("shift+p 0 1 Tab Tab Right Right Tab f i r s t space p i l o t Return Return");
  EXPECT_NE(r.out.find("starting: curvlab run protocols/a_short.toml --participant P01 --db " + db +
                       " --backend headless --new-session --note 'first pilot'"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("exit 0"), std::string::npos) << r.out;
  EXPECT_EQ(count_trials(db, "completed"), 2);  // the earlier session's trial and the new one's
  sqlite3* h = nullptr;
  ASSERT_EQ(sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(h,
                               "SELECT e.session_id, json_extract(e.detail, '$.text') FROM events e "
                               "WHERE e.kind = 'operator_note'",
                               -1, &stmt, nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW);
  EXPECT_EQ(sqlite3_column_int(stmt, 0), 2);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1))), "first pilot");
  sqlite3_finalize(stmt);
  sqlite3_close(h);

  // Escape: nothing started, nothing written.
  r = fill("shift+p 0 2 Escape");
  EXPECT_NE(r.out.find("start form closed: no session started"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("exit 0"), std::string::npos) << r.out;
  EXPECT_EQ(count_trials(db, "completed"), 2);
}
