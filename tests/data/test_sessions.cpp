// `curvlab sessions` after an interruption, through the real executable: a
// file with a completed session, one the operator ended and one killed with
// kill -9 — listed while the last one still runs, then after its death, and
// continued with the very commands the listing prints. Files it cannot read
// are refused as export refuses them; a resume naming a session the file
// lacks says which sessions it holds.
#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/session_list.hpp"
#include "curvlab/harness/data/sha256.hpp"

#include "../cli/run_cli.hpp"
#include "data_files.hpp"
#include "sharing_support.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <unistd.h>

#include <array>
#include <filesystem>
#include <sstream>

using namespace curvlab::harness::data;
using curvlab::testing::run_cli;
using curvlab::testing::scalar;
using Json = nlohmann::json;
namespace fs = std::filesystem;
namespace sh = curvlab::testing::sharing;

namespace {

const std::string demo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("sessions", name); }

// The folder's name holds a blank, so the printed command must quote it.
std::string quoted(const std::string& path) { return "'" + path + "'"; }

Json listing(const std::string& db) {
  const auto r = run_cli("sessions --json --db " + quoted(db));
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto doc = Json::parse(r.out, nullptr, false);
  EXPECT_TRUE(doc.is_array()) << r.out;
  return doc.is_array() ? doc : Json::array();
}

Json session(const Json& list, int id) {
  for (const auto& s : list)
    if (s["session_id"] == id) return s;
  ADD_FAILURE() << "no session " << id << " in " << list.dump(2);
  return Json::object();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::string host_name() {
  std::array<char, 64> host{};
  (void)::gethostname(host.data(), host.size() - 1);
  return host.data();
}

// The table row of session `id` (its line starts with the right-aligned id).
std::string row_of(const std::vector<std::string>& lines, int id) {
  for (const auto& line : lines) {
    std::istringstream words(line);
    std::string first;
    if (words >> first && first == std::to_string(id)) return line;
  }
  return "";
}

// What stands in `row` under the header's column `name`.
std::string column(const std::string& header, const std::string& row, const std::string& name) {
  const auto at = header.find(name);
  if (at == std::string::npos || at >= row.size()) return "";
  const auto begin = row.find_first_not_of(' ', at);
  if (begin == std::string::npos) return "";
  const auto end = row.find("  ", begin);
  return row.substr(begin, end == std::string::npos ? std::string::npos : end - begin);
}

// P01 completes; P02 skips a trial and is ended by the operator.
void completed_and_ended(const fs::path& dir, const std::string& db) {
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --render none --quiet --db " + quoted(db)).exit_code, 0);
  const auto ops = dir / "ops.txt";
  curvlab::testing::write_file(ops, "0.2 skip\n2.0 end\n");
  const auto ended = run_cli("run " + demo + " --participant P02 --render none --quiet --operator-script " +
                             quoted(ops.string()) + " --db " + quoted(db));
  ASSERT_EQ(ended.exit_code, 1) << ended.out;
}

// While P03's session runs: shown running, with its process and host, and
// without a resume command.
void check_live(const std::string& db, const sh::Child& run) {
  const auto live = session(listing(db), 3);
  EXPECT_EQ(live["status"], "running");
  EXPECT_EQ(live["writer"]["pid"], run.pid);
  EXPECT_EQ(live["writer"]["host"], host_name());
  EXPECT_TRUE(live["resume_command"].is_null());
  const auto text = run_cli("sessions --db " + quoted(db));
  EXPECT_EQ(text.exit_code, 0) << text.out;
  EXPECT_NE(row_of(lines_of(text.out), 3).find("being written by process " + std::to_string(run.pid) + " on " +
                                               host_name()),
            std::string::npos)
      << text.out;
}

void check_json(const std::string& db, std::int64_t p03_reported) {
  const auto list = listing(db);
  ASSERT_EQ(list.size(), 3u) << list.dump(2);
  const auto done = session(list, 1), ended = session(list, 2), killed = session(list, 3);
  EXPECT_EQ(done["participant"], "P01");
  EXPECT_EQ(done["protocol"], "demo");
  EXPECT_EQ(done["protocol_version"], "1.0.0");
  EXPECT_EQ(done["protocol_sha256"], scalar(db, "SELECT sha256 FROM protocols"));
  EXPECT_EQ(done["status"], "completed");
  EXPECT_EQ(done["backend"], "headless");
  EXPECT_EQ(done["trials_completed"], 8);
  EXPECT_EQ(done["trials_planned"], 8);
  EXPECT_TRUE(done["resume_command"].is_null());
  EXPECT_GE(done["last_activity_utc"].get<std::string>(), done["started_utc"].get<std::string>());

  EXPECT_EQ(ended["status"], "interrupted");
  EXPECT_EQ(ended["stored_status"], "interrupted");
  EXPECT_EQ(ended["trials_skipped"], 1);
  EXPECT_EQ(ended["trials_completed"],
            std::stoll(scalar(db, "SELECT COUNT(*) FROM trials WHERE session_id = 2 AND status = 'completed'")));
  EXPECT_EQ(ended["resume_command"], "curvlab resume --db " + quoted(db) + " --session 2");

  // Killed: the file still says running, but no process writes it.
  EXPECT_EQ(killed["status"], "interrupted");
  EXPECT_EQ(killed["stored_status"], "running");
  EXPECT_EQ(killed["ended_without_closing"], true);
  EXPECT_TRUE(killed["writer"].is_null());
  EXPECT_GE(killed["trials_completed"].get<std::int64_t>(), p03_reported);
  EXPECT_EQ(killed["resume_command"], "curvlab resume --db " + quoted(db) + " --session 3");
}

// The table: one aligned row per session, each column under its heading.
void check_text(const std::string& db) {
  const auto r = run_cli("sessions --db " + quoted(db));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto lines = lines_of(r.out);
  ASSERT_GE(lines.size(), 4u) << r.out;
  const auto& header = lines.front();
  const std::array<std::string, 3> status{"completed", "interrupted", "interrupted"};
  for (int id = 1; id <= 3; ++id) {
    const auto row = row_of(lines, id);
    EXPECT_EQ(column(header, row, "participant"), "P0" + std::to_string(id)) << r.out;
    EXPECT_EQ(column(header, row, "protocol"), "demo 1.0.0") << r.out;
    EXPECT_EQ(column(header, row, "status"), status[static_cast<std::size_t>(id - 1)]) << r.out;
    EXPECT_EQ(column(header, row, "backend"), "headless") << r.out;
  }
  EXPECT_EQ(column(header, row_of(lines, 1), "done"), "8/8") << r.out;
  EXPECT_EQ(column(header, row_of(lines, 1), "continue"), "-") << r.out;
  EXPECT_EQ(column(header, row_of(lines, 2), "continue"), "curvlab resume --db " + quoted(db) + " --session 2");
  EXPECT_EQ(column(header, row_of(lines, 3), "continue"), "curvlab resume --db " + quoted(db) + " --session 3");
  EXPECT_NE(r.out.find("session 3 is stored running but no process writes it"), std::string::npos) << r.out;
}

}  // namespace

TEST(SessionList, ListedStatusFollowsTheWriter) {
  using S = SessionStatus;
  EXPECT_EQ(listed_status(S::completed, false), S::completed);
  EXPECT_EQ(listed_status(S::completed, true), S::completed);
  EXPECT_EQ(listed_status(S::running, true), S::running);
  EXPECT_EQ(listed_status(S::paused, true), S::running);
  EXPECT_EQ(listed_status(S::interrupted, true), S::running) << "a resume that has just taken the session";
  EXPECT_EQ(listed_status(S::running, false), S::interrupted) << "killed: the file could not say so";
  EXPECT_EQ(listed_status(S::paused, false), S::interrupted);
  EXPECT_EQ(listed_status(S::interrupted, false), S::interrupted);
  EXPECT_EQ(listed_status(S::aborted, false), S::aborted);
}

TEST(CliSessions, ListsARunningAnEndedAndAKilledSessionAndTheirCommandsContinueThem) {
  const auto dir = fresh_dir("listing") / "lab data";
  fs::create_directories(dir);
  const std::string db = (dir / "study.sqlite").string();
  completed_and_ended(dir, db);
  {
    sh::Child run = sh::spawn(CURVLAB_BIN,
                              {"run", demo, "--participant", "P03", "--db", db, "--render", "none", "--pace",
                               "realtime", "--progress", "json"},
                              dir / "p03.out", dir / "p03.err");
    ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 2, std::chrono::seconds(60)))
        << curvlab::testing::read_file(run.err);
    check_live(db, run);
    // The listing cost the session nothing: it goes on.
    EXPECT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 3, std::chrono::seconds(60)));
    run.kill9();
    check_json(db, sh::count_lines(run.out, "\"status\":\"completed\""));
  }
  check_text(db);

  // A resume naming a session the file lacks says which it holds.
  const auto missing = run_cli("resume --db " + quoted(db) + " --session 9 --render none --quiet");
  EXPECT_EQ(missing.exit_code, 2) << missing.out;
  EXPECT_NE(missing.out.find("no session with id 9; the file holds sessions 1 (P01, completed), 2 (P02, "
                             "interrupted), 3 (P03, interrupted); curvlab sessions --db " + db + " lists them"),
            std::string::npos)
      << missing.out;

  // The printed commands are the ones that continue the sessions.
  for (const int id : {2, 3}) {
    const std::string command = session(listing(db), id)["resume_command"];
    ASSERT_EQ(command.rfind("curvlab ", 0), 0u) << command;
    const auto resumed = run_cli(command.substr(8) + " --render none --quiet");
    EXPECT_EQ(resumed.exit_code, 0) << command << "\n" << resumed.out;
  }
  const auto after = listing(db);
  for (const auto& s : after) {
    EXPECT_EQ(s["status"], "completed") << s.dump(2);
    EXPECT_TRUE(s["resume_command"].is_null());
  }
  EXPECT_EQ(session(after, 2)["trials_completed"], 7) << "the skipped trial stays skipped";
  EXPECT_EQ(session(after, 3)["trials_completed"], 8);

  // Listing never writes the file.
  const auto bytes = curvlab::testing::read_file(db);
  ASSERT_EQ(run_cli("sessions --db " + quoted(db)).exit_code, 0);
  EXPECT_EQ(curvlab::testing::read_file(db), bytes);
}

TEST(CliSessions, AFileWithoutSessionsSaysSo) {
  const auto dir = fresh_dir("empty");
  const std::string db = (dir / "empty.sqlite").string();
  ASSERT_TRUE(Database::open(db, OpenMode::create_or_open));
  const auto text = run_cli("sessions --db " + db);
  EXPECT_EQ(text.exit_code, 0) << text.out;
  EXPECT_EQ(text.out, db + ": no sessions\n");
  const auto json = run_cli("sessions --db " + db + " --json");
  EXPECT_EQ(json.exit_code, 0) << json.out;
  EXPECT_EQ(Json::parse(json.out), Json::array());
  const auto resumed = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  EXPECT_EQ(resumed.exit_code, 2) << resumed.out;
  EXPECT_NE(resumed.out.find(db + ": no session with id 1; the file holds no sessions"), std::string::npos)
      << resumed.out;
}

// A missing file, one that is not SQLite, another program's database and one
// written by a newer curvlab: exit 2 with export's very message, the file as
// it was.
TEST(CliSessions, FilesItCannotReadAreRefusedAsExportRefusesThem) {
  const auto dir = fresh_dir("refused");
  const std::string random = (dir / "random.sqlite").string();
  curvlab::testing::write_file(random, std::string(4096, '\x5a'));
  const std::string foreign = (dir / "foreign.sqlite").string();
  Connection::open(foreign, OpenFlags::read_write_create).exec("CREATE TABLE notes (text TEXT)");
  const std::string newer = (dir / "newer.sqlite").string();
  {
    auto db = Database::open(newer, OpenMode::create_or_open);
    ASSERT_TRUE(db);
    db.value().connection().exec("PRAGMA user_version = " + std::to_string(current_schema_version + 1));
  }
  const std::vector<std::pair<std::string, std::string>> files = {
      {(dir / "missing.sqlite").string(), "no such file"},
      {random, "not an SQLite database"},
      {foreign, "not a curvlab data file"},
      {newer, "written with schema version " + std::to_string(current_schema_version + 1) + " by a newer curvlab"}};
  for (const auto& [file, says] : files) {
    const bool existed = fs::exists(file);
    const auto before = existed ? curvlab::testing::read_file(file) : "";
    const auto listed = run_cli("sessions --db " + file);
    EXPECT_EQ(listed.exit_code, 2) << file << "\n" << listed.out;
    EXPECT_NE(listed.out.find(file + ": " + says), std::string::npos) << listed.out;
    const auto exported = run_cli("export --db " + file + " --out " + (dir / "ex").string());
    EXPECT_EQ(listed.out, exported.out);
    EXPECT_EQ(fs::exists(file), existed);
    if (existed) {
      EXPECT_EQ(curvlab::testing::read_file(file), before) << file;
    }
  }
  const auto folder = run_cli("sessions --db " + dir.string());
  EXPECT_EQ(folder.exit_code, 2) << folder.out;
  EXPECT_NE(folder.out.find("is a folder"), std::string::npos) << folder.out;
}

// A session of a version 1 file (read through a migrated copy in memory, the
// file left as it was): listed, but without a command, since it lacks the
// session_start event that resume needs to expand its design again.
TEST(CliSessions, AnOldFilesSessionIsListedButNotOfferedForResume) {
  const auto dir = fresh_dir("v1");
  const std::string db = (dir / "old.sqlite").string();
  {
    auto c = Connection::open(db, OpenFlags::read_write_create);
    c.exec(curvlab::testing::read_file(fs::path(CURVLAB_SCHEMA_DIR) / "v1.sql"));
    c.exec("INSERT INTO protocols VALUES (1, '" + sha256_hex("p") + "', 'p');"
           "INSERT INTO participants VALUES (1, 'P07');"
           "INSERT INTO sessions VALUES (1, 1, 1, 99, 'crashed', '2025-03-01T10:00:00Z');"
           "INSERT INTO trials VALUES (1, 1, 0, '{}', 'convex', 512.5, 'completed');"
           "INSERT INTO trials VALUES (2, 1, 1, '{}', NULL, NULL, 'pending');");
  }
  const auto before = curvlab::testing::read_file(db);
  const auto s = session(listing(db), 1);
  EXPECT_EQ(s["participant"], "P07");
  EXPECT_EQ(s["status"], "interrupted");
  EXPECT_EQ(s["backend"], "unknown");
  EXPECT_EQ(s["trials_completed"], 1);
  EXPECT_EQ(s["trials_planned"], 2);
  EXPECT_TRUE(s["protocol_version"].is_null()) << "the stored text is no protocol";
  EXPECT_TRUE(s["resume_command"].is_null());
  const auto text = run_cli("sessions --db " + db);
  EXPECT_NE(row_of(lines_of(text.out), 1).find("cannot be resumed: its session_start event is missing"),
            std::string::npos)
      << text.out;
  EXPECT_EQ(curvlab::testing::read_file(db), before);
}

namespace {

// The participant registry: a pseudonym run a second time into the same
// file is refused (exit 2, nothing written) naming its earlier session,
// until --new-session says it is meant; `curvlab participants` lists who
// the file holds.
TEST(Participants, ASecondRunOfAPseudonymAsksForNewSessionAndTheListShowsEveryone) {
  const auto dir = fresh_dir("registry");
  const std::string db = (dir / "study.sqlite").string();
  const std::string run = "run " + demo + " --render none --quiet --db " + quoted(db) + " --participant ";
  ASSERT_EQ(run_cli(run + "SIM01").exit_code, 0);
  const auto again = run_cli(run + "SIM01");
  EXPECT_EQ(again.exit_code, 2) << again.out;
  EXPECT_NE(again.out.find("--participant SIM01 already has session 1 (demo 1.0.0, completed 8/8, started "),
            std::string::npos)
      << again.out;
  EXPECT_NE(again.out.find("add --new-session"), std::string::npos) << again.out;
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sessions"), "1") << "the refused run wrote a session";

  ASSERT_EQ(run_cli(run + "SIM01 --new-session").exit_code, 0);
  ASSERT_EQ(run_cli(run + "SIM02").exit_code, 0);
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sessions"), "3");

  const auto listed = run_cli("participants --db " + quoted(db));
  ASSERT_EQ(listed.exit_code, 0) << listed.out;
  EXPECT_NE(listed.out.find("SIM01               2          2"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("1 demo completed, 2 demo completed"), std::string::npos) << listed.out;
  EXPECT_NE(listed.out.find("SIM02               1          1"), std::string::npos) << listed.out;
  const auto json = run_cli("participants --json --db " + quoted(db));
  ASSERT_EQ(json.exit_code, 0) << json.out;
  const Json doc = Json::parse(json.out);
  ASSERT_EQ(doc.size(), 2u);
  EXPECT_EQ(doc[0]["participant"], "SIM01");
  EXPECT_EQ(doc[0]["sessions"].size(), 2u);
  EXPECT_EQ(doc[1]["sessions"][0]["session_id"], 3);
  fs::remove_all(dir);
}

// An unfinished earlier session is offered for resuming instead.
TEST(Participants, AnUnfinishedEarlierSessionIsOfferedForResuming) {
  const auto dir = fresh_dir("registry_unfinished");
  const std::string db = (dir / "study.sqlite").string();
  curvlab::testing::run_shell(std::string(CURVLAB_BIN) + " run " + demo + " --render none --db " + quoted(db) +
                              " --participant SIM01 --progress json 2>/dev/null | head -2 >/dev/null");
  ASSERT_EQ(scalar(db, "SELECT status FROM sessions"), "interrupted");
  const auto again = run_cli("run " + demo + " --render none --db " + quoted(db) + " --participant SIM01");
  EXPECT_EQ(again.exit_code, 2) << again.out;
  EXPECT_NE(again.out.find("continue the unfinished one (curvlab resume --db " + db + " --session 1)"),
            std::string::npos)
      << again.out;
  fs::remove_all(dir);
}

}  // namespace
