// One file, one lock, whatever the path: the ways a lab reached one data
// file by a second path, planted something where curvlab keeps its lock, or
// read the file in a way that took SQLite's locks from a live session. Each
// case is run through the real executable, and the readers are the sqlite3
// module of Debian's Python, as an analyst's script would be.
#include "../cli/run_cli.hpp"
#include "data_files.hpp"
#include "sharing_support.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <thread>

using curvlab::testing::read_file;
using curvlab::testing::run_cli;
using curvlab::testing::run_shell;
using curvlab::testing::scalar;
using curvlab::testing::write_file;
namespace fs = std::filesystem;
namespace sh = curvlab::testing::sharing;

namespace {

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("one_lock", name); }

const std::string demo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

sh::Child start_session(const fs::path& dir, const std::string& db, const std::string& participant = "P01") {
  return sh::start_realtime_session(CURVLAB_BIN, demo, dir, db, participant);
}

std::string integrity(const fs::path& db) { return scalar(db, "PRAGMA integrity_check"); }

std::int64_t completed(const fs::path& db) {
  return std::stoll(scalar(db, "SELECT count(*) FROM trials WHERE status = 'completed'"));
}

// Runs a Python script with the data file as its argument.
int python(const std::string& script, const fs::path& db) {
  const std::string cmd = "/usr/bin/python3 -c '" + script + "' " + db.string() + " >/dev/null 2>&1";
  return std::system(cmd.c_str());
}

// An unfinished SELECT in one connection while another asks for a TRUNCATE
// checkpoint with a 5 s busy timeout: the checkpoint holds the writer's lock
// while it waits for the SELECT.
const std::string checkpointing_reader =
    "import sqlite3, sys\n"
    "a = sqlite3.connect(sys.argv[1], timeout=5)\n"
    "rows = a.execute(\"SELECT * FROM tracking_samples\")\n"
    "rows.fetchone()\n"
    "b = sqlite3.connect(sys.argv[1], timeout=5)\n"
    "try:\n"
    "    b.execute(\"PRAGMA wal_checkpoint(TRUNCATE)\").fetchall()\n"
    "except sqlite3.OperationalError:\n"
    "    pass\n"
    "a.close()\n"
    "b.close()\n";

// A write transaction left open for 8 s, as DB Browser holds one while it
// has unsaved edits.
const std::string open_write_transaction =
    "import sqlite3, sys, time\n"
    "c = sqlite3.connect(sys.argv[1], timeout=5, isolation_level=None)\n"
    "c.execute(\"BEGIN IMMEDIATE\")\n"
    "time.sleep(8)\n"
    "c.execute(\"ROLLBACK\")\n"
    "c.close()\n";

}  // namespace

// Finding: with the session written through a symbolic link, merge --out on
// the real path replaced the file under it (integrity check failed), and
// resume on the real path forked the session. Hard links and `..` paths
// were the same door.
TEST(CliOneLock, EveryPathToTheFileMeetsTheLiveSessionsLock) {
  const auto dir = fresh_dir("paths");
  fs::create_directories(dir / "real");
  fs::create_directories(dir / "links");
  const fs::path real = dir / "real" / "s.sqlite";
  const fs::path link = dir / "links" / "s.sqlite";
  fs::create_symlink("../real/s.sqlite", link);
  const std::string other = (dir / "b.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P02 --db " + other + " --render none --quiet").exit_code, 0);

  sh::Child run = start_session(dir, link.string());
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)))
      << read_file(run.err);
  fs::create_hard_link(real, dir / "hard.sqlite");
  const std::string pid = std::to_string(run.pid);
  for (const fs::path& path : {real, dir / "hard.sqlite", dir / "links" / ".." / "real" / "s.sqlite"}) {
    const auto merged = run_cli("merge --out " + path.string() + " " + other);
    EXPECT_EQ(merged.exit_code, 2) << path << ": " << merged.out;
    EXPECT_NE(merged.out.find("being written by"), std::string::npos) << path << ": " << merged.out;
    const auto resumed = run_cli("resume --db " + path.string() + " --session 1 --render none --quiet");
    EXPECT_EQ(resumed.exit_code, 2) << path << ": " << resumed.out;
    EXPECT_NE(resumed.out.find("session 1 is being written by"), std::string::npos) << resumed.out;
    // SQLite finds the write-ahead log by the file's name, so another name
    // (a hard link) shows only what was checkpointed: not listed here.
    if (path == dir / "hard.sqlite") continue;
    const auto listed = run_cli("sessions --db " + path.string() + " --json");
    EXPECT_NE(listed.out.find("\"running\""), std::string::npos) << path << ": " << listed.out;
    EXPECT_EQ(listed.out.find("curvlab resume"), std::string::npos) << path << ": offered for resume: " << listed.out;
  }
  // The slots name the writer wherever the path resolves to the same name.
  const auto named = run_cli("resume --db " + real.string() + " --session 1 --render none --quiet");
  EXPECT_NE(named.out.find("process " + pid), std::string::npos) << named.out;

  EXPECT_EQ(run.wait(), 0) << read_file(run.err);
  EXPECT_EQ(integrity(real), "ok");
  EXPECT_EQ(completed(real), 8);
  EXPECT_EQ(scalar(real, "SELECT count(*) FROM sessions"), "1") << "nothing was merged into the live file";
}

// Finding: DB.lock was opened through a symbolic link, so curvlab padded
// the link's target with NULs (another file's data lost), or wrote the host
// name into the study's own schema page.
TEST(CliOneLock, ALockFileThatIsALinkOrAnotherFileIsRefusedAndNeverWritten) {
  const auto dir = fresh_dir("companions");
  const fs::path db = dir / "s.sqlite";
  const fs::path thesis = dir / "thesis.txt";
  const std::string text = "Chapter 1. Curved space.\n";
  write_file(thesis, text);

  fs::create_symlink("thesis.txt", dir / "s.sqlite.lock");
  auto r = run_cli("run " + demo + " --participant P01 --db " + db.string() + " --render none --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("s.sqlite.lock is a symbolic link"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(thesis), text) << "the link's target was written";
  EXPECT_TRUE(fs::is_symlink(dir / "s.sqlite.lock")) << "the link was removed, leaving no trace";
  EXPECT_FALSE(fs::exists(db)) << "a refused run made the data file";

  // A study that exists, with its lock file a link to itself.
  fs::remove(dir / "s.sqlite.lock");
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --db " + db.string() + " --render none --quiet").exit_code, 0);
  fs::create_symlink("s.sqlite", dir / "s.sqlite.lock");
  r = run_cli("run " + demo + " --participant P02 --db " + db.string() + " --render none --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  const std::string other = (dir / "other.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P03 --db " + other + " --render none --quiet").exit_code, 0);
  r = run_cli("merge --out " + db.string() + " " + other);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_EQ(integrity(db), "ok");
  EXPECT_EQ(scalar(db, "SELECT count(*) FROM sessions"), "1");

  // A hard link to another file.
  fs::remove(dir / "s.sqlite.lock");
  fs::create_hard_link(thesis, dir / "s.sqlite.lock");
  r = run_cli("run " + demo + " --participant P02 --db " + db.string() + " --render none --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("hard link"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(thesis), text);
}

// Finding: the stale-reserve cleanup deleted a user's folder named
// s.sqlite.reserve-1.keep/ with its files.
TEST(CliOneLock, CleanupRemovesOnlyItsOwnFilesNeverAFolderOrALink) {
  const auto dir = fresh_dir("cleanup");
  const fs::path db = dir / "s.sqlite";
  fs::create_directories(dir / "s.sqlite.reserve-1.keep");
  write_file(dir / "s.sqlite.reserve-1.keep" / "notes.txt", "keep me");
  fs::create_directories(dir / "s.sqlite.reserve-7");
  write_file(dir / "s.sqlite.reserve-7" / "notes.txt", "keep me too");
  write_file(dir / "precious.bin", "precious");
  fs::create_symlink("precious.bin", dir / "s.sqlite.reserve-9");
  // What a writer killed by kill -9 leaves: a reserve of a session no one holds.
  write_file(dir / "s.sqlite.reserve-3", std::string(4096, '\0'));

  const auto r = run_cli("run " + demo + " --participant P01 --db " + db.string() + " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(read_file(dir / "s.sqlite.reserve-1.keep" / "notes.txt"), "keep me");
  EXPECT_EQ(read_file(dir / "s.sqlite.reserve-7" / "notes.txt"), "keep me too");
  EXPECT_TRUE(fs::is_symlink(dir / "s.sqlite.reserve-9"));
  EXPECT_EQ(read_file(dir / "precious.bin"), "precious");
  EXPECT_FALSE(fs::exists(dir / "s.sqlite.reserve-3")) << "a dead writer's reserve is still cleaned up";
}

// Finding: a reader holding an unfinished SELECT while another asked for a
// TRUNCATE checkpoint ended the writer ("database is locked") in 3 of 4
// tries; a write transaction held for 8 s did the same.
TEST(CliOneLock, ReadersThatCheckpointOrHoldTheWriteLockCannotEndASession) {
  const auto dir = fresh_dir("readers");
  for (int round = 0; round < 2; ++round) {
    const fs::path db = dir / ("r" + std::to_string(round) + ".sqlite");
    sh::Child run = start_session(dir, db.string(), "P0" + std::to_string(round + 1));
    ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)))
        << read_file(run.err);
    if (round == 0) {
      for (int k = 0; k < 4 && run.running(); ++k) python(checkpointing_reader, db);
    } else {
      python(open_write_transaction, db);
    }
    EXPECT_EQ(run.wait(), 0) << "round " << round << ": " << read_file(run.err);
    EXPECT_EQ(completed(db), 8) << "round " << round;
    EXPECT_EQ(scalar(db, "SELECT status FROM sessions"), "completed");
    EXPECT_EQ(integrity(db), "ok");
    if (round == 1) {
      EXPECT_NE(scalar(db, "SELECT count(*) FROM events WHERE kind = 'logger_waited'"), "0")
          << "the wait is in the data";
    }
  }
}

// Finding: two sessions started at once on a new file: one exited
// "step: database is locked" in 5 of 15 tries.
TEST(CliOneLock, TwoSessionsStartedAtOnceOnANewFileBothRun) {
  const auto dir = fresh_dir("together");
  for (int round = 0; round < 6; ++round) {
    const fs::path db = dir / ("t" + std::to_string(round) + ".sqlite");
    const std::string cmd = std::string(CURVLAB_BIN) + " run " + demo + " --db " + db.string() +
                            " --render none --quiet --participant ";
    const auto both = run_shell("(" + cmd + "P01 > " + (dir / "a.out").string() + " 2>&1; echo a=$?) & (" + cmd +
                                "P02 > " + (dir / "b.out").string() + " 2>&1; echo b=$?) & wait");
    EXPECT_NE(both.out.find("a=0"), std::string::npos) << read_file(dir / "a.out");
    EXPECT_NE(both.out.find("b=0"), std::string::npos) << read_file(dir / "b.out");
    EXPECT_EQ(scalar(db, "SELECT count(*) FROM sessions WHERE status = 'completed'"), "2") << "round " << round;
  }
}

// Finding: merging a file whose session was still running copied a
// mid-session snapshot that the study then offered for resume.
TEST(CliOneLock, MergeRefusesAnInputWhoseSessionIsBeingWritten) {
  const auto dir = fresh_dir("merge_live");
  const fs::path live = dir / "a.sqlite";
  const fs::path study = dir / "study.sqlite";
  sh::Child run = start_session(dir, live.string());
  ASSERT_TRUE(sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60)))
      << read_file(run.err);
  const auto refused = run_cli("merge --out " + study.string() + " " + live.string());
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("session 1 is being written by process " + std::to_string(run.pid)), std::string::npos)
      << refused.out;
  EXPECT_FALSE(fs::exists(study)) << "a refused merge left a file behind";
  ASSERT_EQ(run.wait(), 0);
  const auto merged = run_cli("merge --out " + study.string() + " " + live.string());
  EXPECT_EQ(merged.exit_code, 0) << merged.out;
  EXPECT_EQ(completed(study), 8);
}

// Findings: merge onto a full disk named its input (on another disk) and
// said to resume; merge and pooled export with a small $TMPDIR demanded
// "at least 64 MiB: a session needs" for a 1 MB merge.
TEST(CliOneLock, MergeAndPooledExportAskForTheSpaceTheyNeedAndNameTheFullDisk) {
  const auto dir = fresh_dir("space");
  sh::ReadOnlyMount small(dir / "small", "size=12m");
  if (!small.ok()) GTEST_SKIP() << "cannot mount a file system here (needs root): " << small.why();
  const std::string a = (dir / "a.sqlite").string();
  const std::string b = (dir / "b.sqlite").string();
  ASSERT_EQ(run_cli("run " + demo + " --participant P01 --db " + a + " --render none --quiet").exit_code, 0);
  ASSERT_EQ(run_cli("run " + demo + " --participant P02 --db " + b + " --render none --quiet").exit_code, 0);

  const std::string tmp = "TMPDIR=" + small.path().string() + " ";
  auto r = run_shell(tmp + CURVLAB_BIN + " export --db " + a + " " + b + " --out " + (dir / "x").string() +
                     " --format csv 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  r = run_cli("merge --out " + (small.path() / "study.sqlite").string() + " " + a + " " + b);
  EXPECT_EQ(r.exit_code, 0) << r.out;

  sh::fill_disk(small.path() / "filler");
  r = run_cli("merge --out " + (small.path() / "study2.sqlite").string() + " " + a + " " + b);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find((small.path() / "study2.sqlite").string()), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("resume"), std::string::npos) << "a merge is not resumed: " << r.out;
  EXPECT_FALSE(fs::exists(small.path() / "study2.sqlite"));
}
