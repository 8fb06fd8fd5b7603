// The data file is shared, as in a lab: readers (curvlab export, the sqlite3
// shell, Python) open it while a session writes it, someone resumes a
// session that is still running or merges onto the file, a write-ahead log
// is damaged after a crash, a schema is damaged by another tool, the file
// sits on read-only media, Ctrl-C ends a session. Each case is run through
// the real executable, the way it went wrong for a lab.
#include "curvlab/harness/data/database.hpp"

#include "../cli/run_cli.hpp"
#include "data_files.hpp"
#include "sharing_support.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

using namespace curvlab::harness::data;
using curvlab::testing::run_cli;
namespace fs = std::filesystem;
namespace sh = curvlab::testing::sharing;

using curvlab::testing::read_file;
using curvlab::testing::scalar;

namespace {

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("sharing", name); }

const std::string demo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

sh::Child start_session(const fs::path& dir, const std::string& db, const std::string& participant = "P01") {
  return sh::start_realtime_session(CURVLAB_BIN, demo, dir, db, participant);
}

std::int64_t stored_completed(const std::string& db) {
  auto c = Connection::open(db, OpenFlags::read_only);
  return c.query_int("SELECT count(*) FROM trials WHERE status = 'completed'");
}

std::string session_status(const std::string& db, int session) {
  auto c = Connection::open(db, OpenFlags::read_only);
  Statement s(c, "SELECT status FROM sessions WHERE session_id = ?1");
  s.bind(1, std::int64_t{session});
  return s.step() ? s.column_text(0) : "missing";
}

}  // namespace

// Finding: a reader closing the file made the writer's committed trials
// vanish after a crash (an ifstream in the writer process dropped its
// SQLite locks, so the reader's close deleted the write-ahead log).
TEST(CliSharing, ReadersDuringASessionThenKillNineLoseNoCompletedTrial) {
  const auto dir = fresh_dir("readers");
  std::mt19937 rng(20261125);
  std::int64_t reported_total = 0;
  for (int round = 0; round < 3; ++round) {
    const std::string db = (dir / ("k" + std::to_string(round) + ".sqlite")).string();
    sh::Child run = start_session(dir, db);
    ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)))
        << curvlab::testing::read_file(run.err);
    const auto stop_at = std::chrono::steady_clock::now() +
                         std::chrono::milliseconds(std::uniform_int_distribution<int>(1500, 4000)(rng));
    for (int k = 0; std::chrono::steady_clock::now() < stop_at; ++k) sh::read_once(CURVLAB_BIN, db, dir, k);
    run.kill9();
    const std::int64_t reported = sh::count_lines(run.out, "\"status\":\"completed\"");
    EXPECT_GE(stored_completed(db), reported) << "round " << round << ": a reader cost the session its trials";
    reported_total += reported;
  }
  EXPECT_GT(reported_total, 0);
}

// Finding: resume of a session still being written was accepted and
// corrupted the file; merge --out onto it silently lost trials.
TEST(CliSharing, ALiveSessionCannotBeResumedOrReplacedAndADeadOneResumesAtOnce) {
  const auto dir = fresh_dir("writer");
  const std::string db = (dir / "rr.sqlite").string();
  const std::string other = (dir / "other.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P02 --db " + other + " --render none --quiet").exit_code, 0);
  sh::Child run = start_session(dir, db);
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)))
      << curvlab::testing::read_file(run.err);

  const auto resumed = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  EXPECT_EQ(resumed.exit_code, 2) << resumed.out;
  EXPECT_NE(resumed.out.find("session 1 is being written by process " + std::to_string(run.pid)),
            std::string::npos)
      << resumed.out;
  EXPECT_NE(resumed.out.find("nothing was changed"), std::string::npos) << resumed.out;

  const auto merged = run_cli("merge --out " + db + " " + other);
  EXPECT_EQ(merged.exit_code, 2) << merged.out;
  EXPECT_NE(merged.out.find("is being written by process " + std::to_string(run.pid)), std::string::npos)
      << merged.out;

  // The refusals changed nothing: the session goes on and is killed later.
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 3, std::chrono::seconds(60)));
  run.kill9();
  const std::int64_t reported = sh::count_lines(run.out, "\"status\":\"completed\"");
  EXPECT_GE(stored_completed(db), reported);
  EXPECT_EQ(session_status(db, 1), "running") << "killed: no chance to store anything else";

  // Its writer is dead: resumable at once, no unlock step.
  const auto again = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  EXPECT_EQ(again.exit_code, 0) << again.out;
  EXPECT_EQ(session_status(db, 1), "completed");
  EXPECT_EQ(stored_completed(db), 8);
  // And the file can be merged into now.
  EXPECT_EQ(run_cli("merge --out " + db + " " + other).exit_code, 0);
}

// Finding: a one-byte change in the write-ahead log's header after a crash
// made export write a fresh schema and delete the log with the trials.
TEST(CliSharing, ADamagedWriteAheadLogIsReportedAndKept) {
  const auto dir = fresh_dir("wal");
  const std::string db = (dir / "t.sqlite").string();
  sh::Child run = start_session(dir, db);
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 2, std::chrono::seconds(60)));
  run.kill9();
  ASSERT_TRUE(fs::exists(db + "-wal"));
  ASSERT_GT(fs::file_size(db + "-wal"), 32u) << "the committed trials should still be in the log";
  std::string wal = curvlab::testing::read_file(db + "-wal");
  wal[24] = static_cast<char>(wal[24] ^ 0x5a);
  curvlab::testing::write_file(db + "-wal", wal);
  const std::string main_before = curvlab::testing::read_file(db);

  for (const std::string& args :
       {"export --db " + db + " --out " + (dir / "ex").string(), "resume --db " + db + " --session 1 --render none",
        "replay --db " + db + " --session 1 --trial 0 --out " + (dir / "replay").string(),
        "run " + demo + " --participant P03 --db " + db + " --render none --quiet",
        "merge --out " + (dir / "m.sqlite").string() + " " + db}) {
    const auto r = run_cli(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out;
    EXPECT_NE(r.out.find("write-ahead log"), std::string::npos) << args << "\n" << r.out;
    EXPECT_NE(r.out.find("Nothing was changed"), std::string::npos) << args << "\n" << r.out;
  }
  EXPECT_EQ(curvlab::testing::read_file(db + "-wal"), wal) << "the log was modified";
  EXPECT_EQ(curvlab::testing::read_file(db), main_before) << "the file was modified";
  EXPECT_FALSE(fs::exists(dir / "ex"));
}

// Findings: run on a file damaged inside left a new session in it; a
// damaged schema exited 1 with raw SQL (or a JSON library's message).
TEST(CliSharing, DamagedFilesAndSchemasExitTwoWithOneMessageAndStayAsTheyWere) {
  const auto dir = fresh_dir("schema");
  const std::string good = (dir / "good.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --db " + good + " --render none --quiet").exit_code, 0);
  struct Damage {
    std::string label;
    std::string sql;  // applied with a plain connection
  };
  const std::vector<Damage> damages = {
      {"dropped table", "DROP TABLE trials"},
      {"user_version 0", "PRAGMA user_version = 0"},
      {"user_version -1", "PRAGMA user_version = -1"},
      {"user_version 2", "PRAGMA user_version = 2"},
      {"missing column frames.late", "ALTER TABLE frames DROP COLUMN late"},
      {"stored JSON of the wrong shape",
       "UPDATE events SET detail = json_set(detail, '$.participant_number', 'one') WHERE kind = 'session_start'; "
       "UPDATE sessions SET status = 'interrupted'"},
  };
  for (const auto& d : damages) {
    const std::string db = (dir / "damaged.sqlite").string();
    remove_database_files(db);
    fs::copy_file(good, db);
    {
      auto c = Connection::open(db, OpenFlags::read_write);
      c.exec("PRAGMA foreign_keys = OFF");
      c.exec(d.sql);
      c.exec("PRAGMA wal_checkpoint(TRUNCATE)");
    }
    const std::string before = curvlab::testing::read_file(db);
    std::vector<std::string> commands = {"resume --db " + db + " --session 1 --render none --quiet"};
    if (d.label != "stored JSON of the wrong shape") {
      commands.push_back("run " + demo + " --participant P09 --db " + db + " --render none --quiet");
      commands.push_back("export --db " + db + " --out " + (dir / "ex").string());
      commands.push_back("merge --out " + (dir / "m.sqlite").string() + " " + db);
      commands.push_back("replay --db " + db + " --session 1 --trial 0 --out " + (dir / "replay").string());
    }
    for (const auto& args : commands) {
      const auto r = run_cli(args);
      EXPECT_EQ(r.exit_code, 2) << d.label << ": " << args << "\n" << r.out;
      EXPECT_NE(r.out.find("damaged curvlab data file"), std::string::npos) << d.label << ": " << args << "\n"
                                                                           << r.out;
      EXPECT_NE(r.out.find(".recover | sqlite3 recovered.sqlite"), std::string::npos) << d.label << "\n" << r.out;
      EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << d.label << ": " << args << ": expected one line\n" << r.out;
    }
    EXPECT_EQ(curvlab::testing::read_file(db), before) << d.label << ": the file was modified";
    EXPECT_FALSE(fs::exists(dir / "ex")) << d.label;
    EXPECT_FALSE(fs::exists(dir / "m.sqlite")) << d.label;
  }
}

TEST(CliSharing, RunOnAFileDamagedInsideAddsNoSession) {
  const auto dir = fresh_dir("inside");
  const std::string db = (dir / "d.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --db " + db + " --render none --quiet").exit_code, 0);
  {
    auto c = Connection::open(db, OpenFlags::read_write);
    c.exec("PRAGMA wal_checkpoint(TRUNCATE)");
  }
  std::string bytes = curvlab::testing::read_file(db);
  // Damage the trials table's pages, as a failing disk does, keeping page 1.
  const std::int64_t page = [&] {
    auto c = Connection::open(db, OpenFlags::read_only);
    return c.query_int("SELECT rootpage FROM sqlite_master WHERE name = 'trials'");
  }();
  bytes.replace(static_cast<std::size_t>(page - 1) * 4096, 16, std::string(16, '\xff'));
  curvlab::testing::write_file(db, bytes);
  const auto r = run_cli("run " + demo + " --participant P02 --db " + db + " --render none --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("damaged curvlab data file"), std::string::npos) << r.out;
  EXPECT_EQ(curvlab::testing::read_file(db), bytes) << "a session was added to a damaged file";
  EXPECT_FALSE(fs::exists(db + "-wal") && fs::file_size(db + "-wal") > 0);
}

// Finding: export, merge, replay and resume failed with "unable to open
// database file" on read-only media (an archive disc, a protected share).
TEST(CliSharing, ReadOnlyMediaAreReadAndNeverWritten) {
  const auto dir = fresh_dir("media");
  sh::ReadOnlyMount mount(dir / "disc");
  if (!mount.ok()) GTEST_SKIP() << "cannot mount a file system here (needs root): " << mount.why();
  const std::string db = (mount.path() / "study.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --db " + db + " --render none --quiet").exit_code, 0);
  sh::Child run = start_session(dir, db, "P02");
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 2, std::chrono::seconds(60)));
  run.kill9();  // the second session's trials are still in the log
  ASSERT_TRUE(fs::exists(db + "-wal"));
  // A second disc holds a finished file alone, without -wal or -shm.
  ASSERT_TRUE(mount.make_read_only()) << mount.why();

  const auto ex = run_cli("export --db " + db + " --out " + (dir / "ex").string() + " --json");
  EXPECT_EQ(ex.exit_code, 0) << ex.out;
  EXPECT_FALSE(fs::is_empty(dir / "ex")) << "nothing was exported";
  const auto rp = run_cli("replay --db " + db + " --session 2 --trial 0 --out " + (dir / "replay").string());
  EXPECT_EQ(rp.exit_code, 0) << rp.out;
  const auto mg = run_cli("merge --out " + (dir / "m.sqlite").string() + " " + db);
  EXPECT_EQ(mg.exit_code, 0) << mg.out;
  EXPECT_GE(stored_completed((dir / "m.sqlite").string()), 10) << "the log's trials were merged too";
  const auto rs = run_cli("resume --db " + db + " --session 2 --render none --quiet");
  EXPECT_EQ(rs.exit_code, 1) << rs.out;
  EXPECT_NE(rs.out.find("not writable"), std::string::npos) << rs.out;

  sh::ReadOnlyMount second(dir / "disc2");
  ASSERT_TRUE(second.ok()) << second.why();
  const std::string alone = (second.path() / "alone.sqlite").string();
  ASSERT_EQ(run_cli("merge --out " + alone + " " + (dir / "m.sqlite").string()).exit_code, 0);
  ASSERT_FALSE(fs::exists(alone + "-wal"));
  ASSERT_TRUE(second.make_read_only()) << second.why();
  const auto ex2 = run_cli("export --db " + alone + " --out " + (dir / "ex2").string());
  EXPECT_EQ(ex2.exit_code, 0) << ex2.out;
  const auto mg2 = run_cli("merge --out " + (dir / "m2.sqlite").string() + " " + alone);
  EXPECT_EQ(mg2.exit_code, 0) << mg2.out;
}

// Finding: Ctrl-C exited 130 leaving the session "running".
TEST(CliSharing, ASignalEndsTheSessionInterruptedWithTheResumeCommand) {
  const auto dir = fresh_dir("signal");
  for (const int sig : {SIGINT, SIGTERM, SIGHUP}) {
    const std::string db = (dir / ("s" + std::to_string(sig) + ".sqlite")).string();
    sh::Child run = start_session(dir, db, "S" + std::to_string(sig));
    ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)));
    const int status = run.signal_and_wait(sig);
    ASSERT_TRUE(WIFEXITED(status)) << "signal " << sig << " killed the process instead of ending the session";
    EXPECT_EQ(WEXITSTATUS(status), 128 + sig);
    EXPECT_EQ(session_status(db, 1), "interrupted");
    const std::string err = curvlab::testing::read_file(run.err);
    EXPECT_NE(err.find("curvlab resume --db " + db + " --session 1"), std::string::npos) << err;
    EXPECT_EQ(stored_completed(db), sh::count_lines(run.out, "\"status\":\"completed\""));
  }
}

// Finding: after the disk filled, the session stayed "running".
TEST(CliSharing, AFullDiskEndsTheSessionInterruptedAndResumable) {
  const auto dir = fresh_dir("full");
  sh::ReadOnlyMount disk(dir / "disk", "size=80m");
  if (!disk.ok()) GTEST_SKIP() << "cannot mount a file system here (needs root): " << disk.why();
  const std::string db = (disk.path() / "f.sqlite").string();
  sh::Child run = start_session(dir, db);
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 2, std::chrono::seconds(60)))
      << curvlab::testing::read_file(run.err);
  const fs::path filler = disk.path() / "filler";
  sh::fill_disk(filler);
  const int status = run.wait();
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
  const std::string err = curvlab::testing::read_file(run.err);
  EXPECT_NE(err.find("disk is full"), std::string::npos) << err;
  EXPECT_NE(err.find("curvlab resume --db " + db + " --session 1"), std::string::npos) << err;
  fs::remove(filler);
  EXPECT_EQ(session_status(db, 1), "interrupted");
  EXPECT_GE(stored_completed(db), sh::count_lines(run.out, "\"status\":\"completed\""));
  const auto again = run_cli("resume --db " + db + " --session 1 --render none --quiet");
  EXPECT_EQ(again.exit_code, 0) << again.out;
  EXPECT_EQ(stored_completed(db), 8);
  EXPECT_FALSE(fs::exists(db + ".reserve-1")) << "the reserve outlived its session";
}
