// What the program does with the files and options people hand it, through
// the real executable: a text file that is not UTF-8 (Windows Notepad's
// Latin-1), a pseudonym whose number does not fit, a coordinate no lab can
// hold, a frame whose head pose was not finite, and a --progress json reader
// that goes away. Each is refused, or ends the session resumable, before it
// can become wrong data.
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

using curvlab::testing::fresh_dir;
using curvlab::testing::query;
using curvlab::testing::run_cli;
using curvlab::testing::run_shell;
namespace fs = std::filesystem;

namespace {

const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

std::string write(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
  return path.string();
}

std::string read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The demo protocol's text with `from` replaced by `to` (once).
std::string demo_with(const std::string& from, const std::string& to) {
  std::string text = read(kDemo);
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string run_demo(const fs::path& db, const std::string& participant, const std::string& more = "") {
  return "run " + kDemo + " --participant " + participant + " --db " + db.string() + " --render none --quiet " + more;
}

}  // namespace

// ---- text files that are not UTF-8 -----------------------------------------

// A note saved by Notepad in Latin-1 (é = 0xE9) passed the script check and
// ended the session at that note with a JSON library's message; it is
// refused at load, naming file, line, byte and column, before a session is
// written.
TEST(InputFiles, ALatin1OperatorNoteIsRefusedBeforeASessionIsWritten) {
  const auto dir = fresh_dir("input_latin1_note");
  const auto ops = write(dir / "ops.txt", "0.2 pause\n0.5 resume\n0.6 note caf\xE9 spilled\n");
  const auto r = run_cli(run_demo(dir / "s.sqlite", "P01", "--operator-script " + ops));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(ops + ":3: the operator script is not UTF-8 (byte 0xE9 at column 13); save the file as UTF-8"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("json.exception"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
}

// Protocols go through toml++, which refuses such bytes too; the message
// says which byte, where, and what to do, as for every other file.
TEST(InputFiles, ALatin1ProtocolIsNamedByLineAndByte) {
  const auto dir = fresh_dir("input_latin1_protocol");
  const auto protocol = write(dir / "cafe.toml", demo_with("prompt = \"Convex", "prompt = \"Caf\xE9 convex"));
  const auto r = run_cli("validate " + protocol);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(protocol + ":47:14: error: syntax: not UTF-8 (byte 0xE9 at column 14); save the file as UTF-8"),
            std::string::npos)
      << r.out;
}

TEST(InputFiles, ALatin1TrajectoryOrTouchesFileIsNamedByLine) {
  const auto dir = fresh_dir("input_latin1_csv");
  const auto touches = write(dir / "touches.csv", "x_m,y_m,z_m\n# touched by Ren\xE9\n0,0.75,0\n");
  const auto r = run_cli("calibrate --touches " + touches);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(touches + ":2: the touches file is not UTF-8 (byte 0xE9 at column 17)"), std::string::npos)
      << r.out;
  ASSERT_EQ(run_cli("trajectory walk-around --laps 1 --out " + (dir / "walk.csv").string()).exit_code, 0);
  const auto trajectory = write(dir / "latin1.csv", "# Ren\xE9's walk\n" + read(dir / "walk.csv"));
  const auto t = run_cli("track --trajectory " + trajectory + " --space E3 --algorithm naive --json");
  EXPECT_EQ(t.exit_code, 2) << t.out.substr(0, 400);
  EXPECT_NE(t.out.find(trajectory + ":1: the trajectory file is not UTF-8 (byte 0xE9 at column 6)"),
            std::string::npos)
      << t.out.substr(0, 400);
}

// ---- participant numbers from pseudonyms -----------------------------------

// A trailing number of ten digits fell back to participant 1: P1000000000
// ran with P1's seed and counterbalancing row. It is refused, naming the
// option and the way out; two distinct pseudonyms never share a number.
TEST(InputFiles, APseudonymNumberBeyondNineDigitsIsRefusedNotFoldedOntoParticipant1) {
  const auto dir = fresh_dir("input_pseudonym_number");
  const auto db = dir / "s.sqlite";
  ASSERT_EQ(run_cli(run_demo(db, "P1")).exit_code, 0);
  const auto r = run_cli(run_demo(db, "P1000000000"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--participant P1000000000: its trailing number 1000000000 is larger than 999999999"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("--participant-number"), std::string::npos) << r.out;
  // Given explicitly, the number is the one stored.
  ASSERT_EQ(run_cli(run_demo(db, "P1000000000", "--participant-number 1000000000")).exit_code, 0);
  ASSERT_EQ(run_cli(run_demo(db, "P999999999")).exit_code, 0);
  EXPECT_EQ(query(db.string(), "SELECT p.pseudonym, json_extract(e.detail, '$.participant_number') FROM events e "
                               "JOIN sessions s ON s.session_id = e.session_id JOIN participants p "
                               "ON p.participant_id = s.participant_id WHERE e.kind = 'session_start' "
                               "ORDER BY s.session_id"),
            (std::vector<std::vector<std::string>>{
                {"P1", "1"}, {"P1000000000", "1000000000"}, {"P999999999", "999999999"}}));
}

// `--participant P00` was answered with "--participant-number must be at
// least 1", an option never given.
TEST(InputFiles, AZeroPseudonymNumberNamesTheOptionGiven) {
  const auto dir = fresh_dir("input_pseudonym_zero");
  const auto r = run_cli(run_demo(dir / "s.sqlite", "P00"));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--participant P00: its trailing number 00 is 0; participant numbers start at 1 "
                       "(or give --participant-number N)"),
            std::string::npos)
      << r.out;
  EXPECT_EQ(r.out.find("--participant-number must be at least 1"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
}

// ---- coordinates no lab can hold -------------------------------------------

// A trajectory position of 1e308 m was tracked (and `run --trajectory`
// logged it); it is refused with file, line, column and field.
TEST(InputFiles, ATrajectoryPositionOutsideTheLabVolumeIsRefused) {
  const auto dir = fresh_dir("input_trajectory_bound");
  ASSERT_EQ(run_cli("trajectory walk-around --laps 1 --out " + (dir / "walk.csv").string()).exit_code, 0);
  std::string text = read(dir / "walk.csv");
  // The first data row (line 4) begins "0,1,0,": its head_x_m is the 0 at column 5.
  const auto row = text.find("\n0,1,0,");
  ASSERT_NE(row, std::string::npos);
  text.replace(row + 5, 1, "1e308");
  const auto big = write(dir / "big.csv", text);
  const auto r = run_cli("track --trajectory " + big + " --space H3 --edge-m 1 --algorithm table-anchored --json");
  EXPECT_EQ(r.exit_code, 2) << r.out.substr(0, 400);
  EXPECT_NE(r.out.find(big + ":4:5: field 'head_x_m': expected a lab coordinate in metres within ±100 (the lab "
                             "volume), got '1e308'"),
            std::string::npos)
      << r.out.substr(0, 400);
  const auto run = run_cli(run_demo(dir / "s.sqlite", "P01", "--trajectory " + big));
  EXPECT_EQ(run.exit_code, 2) << run.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
}

TEST(InputFiles, ATouchOrCalibrationOutsideTheLabVolumeIsRefused) {
  const auto dir = fresh_dir("input_calibration_bound");
  const auto touches = write(dir / "touches.csv", "x_m,y_m,z_m\n-0.5,0.75,0.5\n0.5,0.75,0.5\n"
                                                  "1e308,0.75,-0.5\n-0.5,0.75,-0.5\n");
  const auto t = run_cli("calibrate --touches " + touches);
  EXPECT_EQ(t.exit_code, 2) << t.out;
  EXPECT_NE(t.out.find(touches + ":4: x_m: expected a lab coordinate in metres within ±100 (the lab volume), got "
                                 "'1e308'"),
            std::string::npos)
      << t.out;

  const auto calibration = write(dir / "table.json", "{\n  \"centre_x_m\": 1e308,\n  \"centre_z_m\": 0.0,\n"
                                                     "  \"yaw_rad\": 0.0,\n  \"edge_m\": 1.0,\n  \"height_m\": 0.75\n}\n");
  const auto r = run_cli(run_demo(dir / "s.sqlite", "P01", "--calibration " + calibration));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(calibration + ":2: centre_x_m: expected metres within ±100 (the lab volume), got 1e+308"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));

  // JSON has no NaN or infinity; a number beyond a double's range does not parse.
  const auto huge = write(dir / "huge.json",
                          "{\n  \"centre_x_m\": 0.0,\n  \"centre_z_m\": 1e400,\n"
                          "  \"yaw_rad\": 0.0,\n  \"edge_m\": 1.0,\n  \"height_m\": 0.75\n}\n");
  const auto h = run_cli(run_demo(dir / "s.sqlite", "P01", "--calibration " + huge));
  EXPECT_EQ(h.exit_code, 2) << h.out;
  EXPECT_NE(h.out.find(huge + ":3: not valid JSON here"), std::string::npos) << h.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
}

// ---- replaying a frame whose head pose is not finite -----------------------

// A file written before non-finite poses were stored as lost holds a NaN
// head pose; replaying that frame drew a black image and exited 0. It is
// refused with the reason and the trial's frames that can be replayed.
TEST(InputFiles, ReplayOfAFrameWithoutAFiniteHeadPoseIsRefused) {
  const auto dir = fresh_dir("input_replay_nan");
  const auto db = (dir / "s.sqlite").string();
  ASSERT_EQ(run_cli(run_demo(dir / "s.sqlite", "P01")).exit_code, 0);
  const std::string onset =
      query(db, "SELECT json_extract(e.detail, '$.frame_index') FROM events e JOIN trials t ON t.trial_id = e.trial_id "
                "WHERE e.kind = 'onset' AND t.trial_index = 0")[0][0];
  std::string nan_blob = "X'";
  for (int k = 0; k < 16; ++k) nan_blob += "000000000000F87F";  // quiet NaN, little-endian
  nan_blob += "'";
  {
    auto file = curvlab::harness::data::Database::open(db, curvlab::harness::data::OpenMode::open_existing);
    ASSERT_TRUE(file);
    file.value().connection().exec("UPDATE tracking_samples SET virtual_pose = " + nan_blob +
                                   " WHERE device = 'head' AND frame_index = " + onset);
  }
  const auto r = run_cli("replay --db " + db + " --session 1 --trial 0 --software --out " + (dir / "replay").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("frame " + onset + " of trial 0 has no valid head pose"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "replay" / "left.png"));
}

// ---- a --progress json reader that goes away ---------------------------------

// `run --progress json | head -3`: the write after head exits killed the
// process by SIGPIPE and left the session stored `running`. The session now
// ends interrupted (resumable), exit 1 with the reason on stderr.
TEST(InputFiles, AProgressReaderThatExitsLeavesTheSessionInterrupted) {
  const auto dir = fresh_dir("input_progress_pipe");
  const auto db = (dir / "s.sqlite").string();
  const auto err = (dir / "stderr.txt").string();
  const auto r = run_shell("bash -c '" + std::string(CURVLAB_BIN) + " run " + kDemo + " --participant P01 --db " + db +
                           " --render none --progress json --pace realtime 2>" + err +
                           " | head -3 >/dev/null; echo exit=${PIPESTATUS[0]}'");
  EXPECT_NE(r.out.find("exit=1"), std::string::npos) << r.out << read(err);
  EXPECT_NE(read(err).find("standard output was closed"), std::string::npos) << read(err);
  const auto listed = run_cli("sessions --db " + db + " --json");
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  const auto sessions = nlohmann::json::parse(listed.out);
  ASSERT_EQ(sessions.size(), 1u) << listed.out;
  EXPECT_EQ(sessions[0]["status"], "interrupted") << listed.out;
  EXPECT_EQ(sessions[0]["stored_status"], "interrupted") << listed.out;
  EXPECT_EQ(sessions[0]["ended_without_closing"], false) << listed.out;
  EXPECT_EQ(query(db, "SELECT json_extract(detail, '$.signal') FROM events WHERE kind = 'signal'"),
            (std::vector<std::vector<std::string>>{{"13"}}));
  const auto resumed = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  EXPECT_EQ(resumed.exit_code, 0) << resumed.out;
  EXPECT_EQ(query(db, "SELECT status FROM sessions")[0][0], "completed");
}
