// Readers during a session, then kill -9: the way a lab lost trials. Each
// round starts a realtime demo session through a symbolic link to the data
// file; curvlab export, the sqlite3 shell and Python's sqlite3 take turns on
// the file with two harder readers (every second read): one that asks for a
// TRUNCATE checkpoint under an unfinished SELECT, and one that holds a write
// transaction open for 6 s (longer than SQLite's 5 s busy timeout, as DB
// Browser does with unsaved edits). The round tries `merge --out` onto the
// file's real path, kills the session at a random instant, compares the
// trials it reported completed with the trials stored, and checks the file's
// integrity. A session that fails on its own before the kill was ended by a
// reader. Usage:
//   bench_readers_kill [ROUNDS] [--no-merge] [CURVLAB ...]
// (--no-merge leaves the merge out, to see what the readers alone do to an
// older build whose merge would replace the file under its session).
// Several executables (an older build beside this one) are measured in the
// same run, round for round on the same kill instants.
#include "curvlab/harness/data/database.hpp"
#include "sharing_support.hpp"

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>


namespace fs = std::filesystem;
namespace sh = curvlab::testing::sharing;
using curvlab::harness::data::Connection;
using curvlab::harness::data::OpenFlags;

namespace {

struct Tally {
  int rounds = 0;
  int rounds_losing = 0;
  std::int64_t reported = 0;
  std::int64_t lost = 0;
  int reads = 0;
  int ended_by_reader = 0;    // sessions that exited before the kill
  int merges_accepted = 0;    // merge --out onto the live file that exited 0
  int integrity_failures = 0;
};

// The readers a lab's tools add to the bench's usual three: a checkpoint
// under an unfinished SELECT, a write transaction held open for 6 s.
void hard_read(const fs::path& db, int turn) {
  const std::string checkpoint =
      "import sqlite3, sys\n"
      "a = sqlite3.connect(sys.argv[1], timeout=5)\n"
      "rows = a.execute('SELECT * FROM tracking_samples'); rows.fetchone()\n"
      "b = sqlite3.connect(sys.argv[1], timeout=5)\n"
      "try:\n    b.execute('PRAGMA wal_checkpoint(TRUNCATE)').fetchall()\n"
      "except sqlite3.OperationalError:\n    pass\n";
  const std::string hold =
      "import sqlite3, sys, time\n"
      "c = sqlite3.connect(sys.argv[1], timeout=5, isolation_level=None)\n"
      "c.execute('BEGIN IMMEDIATE'); time.sleep(6); c.execute('ROLLBACK')\n";
  const std::string cmd = "/usr/bin/python3 -c \"" + (turn % 2 == 0 ? checkpoint : hold) + "\" " + db.string() +
                          " >/dev/null 2>&1";
  (void)!std::system(cmd.c_str());
}

std::string integrity(const std::string& db) {
  try {
    auto c = Connection::open(db, OpenFlags::read_only);
    curvlab::harness::data::Statement s(c, "PRAGMA integrity_check");
    return s.step() ? s.column_text(0) : "no result";
  } catch (const std::exception& e) {
    return e.what();
  }
}

std::int64_t stored_completed(const std::string& db) {
  try {
    auto c = Connection::open(db, OpenFlags::read_only);
    return c.query_int("SELECT count(*) FROM trials WHERE status = 'completed'");
  } catch (const std::exception&) {
    return 0;
  }
}

bool with_merge = true;

void round(const std::string& bin, const fs::path& dir, int k, int kill_after_ms, Tally& t) {
  std::string name = "r";  // appended step by step: GCC 12's -Wrestrict misfires on "r" + to_string(k)
  name += std::to_string(k);
  name += ".sqlite";
  fs::create_directories(dir / "real");
  fs::create_directories(dir / "links");
  const std::string db = (dir / "real" / name).string();
  const fs::path link = dir / "links" / name;
  curvlab::harness::data::remove_database_files(db);
  fs::remove(link);
  fs::create_symlink(fs::path("..") / "real" / name, link);
  // The last round's output must not answer for this one's first trial.
  fs::remove(dir / "run.out");
  fs::remove(dir / "run.err");
  sh::Child run = sh::spawn(bin,
                            {"run", std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml", "--participant", "P01",
                             "--db", link.string(), "--render", "none", "--pace", "realtime", "--progress", "json"},
                            dir / "run.out", dir / "run.err");
  if (!sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60))) return;
  const auto stop_at = std::chrono::steady_clock::now() + std::chrono::milliseconds(kill_after_ms);
  const std::string merge =
      bin + " merge --out " + db + " " + (dir / "other.sqlite").string() + " > " + (dir / "merge.out").string() + " 2>&1";
  if (with_merge && std::system(merge.c_str()) == 0) {
    ++t.merges_accepted;
    std::fprintf(stderr, "\n%s round %d: merge --out onto the live file was accepted: %s\n", bin.c_str(), k,
                 curvlab::testing::read_file(dir / "merge.out").c_str());
  }
  for (int r = 0; std::chrono::steady_clock::now() < stop_at && run.running(); ++r, ++t.reads) {
    if (r % 2 == 1) hard_read(db, k + r / 2);  // rounds alternate which hard reader comes first
    else sh::read_once(bin, db, dir, r);
  }
  // A writer that a reader made give up needs a moment to end its session.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  if (!run.running()) {
    // Ended on its own: by a reader when it failed, else it simply finished.
    const int status = run.wait();
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) {
      ++t.ended_by_reader;
      const std::string err = curvlab::testing::read_file(dir / "run.err");
      std::fprintf(stderr, "\n%s round %d: the session ended: %s\n", bin.c_str(), k,
                   err.substr(err.size() > 300 ? err.size() - 300 : 0).c_str());
    }
  }
  run.kill9();
  const std::int64_t reported = sh::count_lines(run.out, "\"status\":\"completed\"");
  const std::int64_t stored = stored_completed(db);
  ++t.rounds;
  t.reported += reported;
  if (stored < reported) {
    ++t.rounds_losing;
    t.lost += reported - stored;
  }
  if (integrity(db) != "ok") ++t.integrity_failures;
  curvlab::harness::data::remove_database_files(db);
  for (const char* companion : {".lock", ".reserve-1"}) fs::remove(db + companion);
  fs::remove(link);
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 50;
  std::vector<std::string> bins;
  for (int i = 2; i < argc; ++i) {
    if (std::string(argv[i]) == "--no-merge") with_merge = false;
    else bins.emplace_back(argv[i]);
  }
  if (bins.empty()) bins.push_back((fs::path(argv[0]).parent_path() / "curvlab").string());
  const fs::path dir = fs::temp_directory_path() / ("curvlab_bench_readers_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<Tally> tallies(bins.size());
  // The file each round tries to merge onto the live one.
  const std::string other = (dir / "other.sqlite").string();
  const std::string make_other = bins.front() + " run " + std::string(CURVLAB_SOURCE_DIR) +
                                 "/protocols/demo.toml --participant P02 --render none --quiet --db " + other;
  if (std::system(make_other.c_str()) != 0) std::fprintf(stderr, "could not make %s\n", other.c_str());
  std::mt19937 rng(20261125);
  for (int k = 0; k < rounds; ++k) {
    const int kill_after_ms = std::uniform_int_distribution<int>(1500, 4500)(rng);
    for (std::size_t b = 0; b < bins.size(); ++b) round(bins[b], dir, k, kill_after_ms, tallies[b]);
    std::fprintf(stderr, "\rround %d/%d", k + 1, rounds);
  }
  std::fprintf(stderr, "\n");
  std::printf("%-40s %6s %6s %9s %6s %7s %7s %7s %9s\n", "curvlab", "rounds", "reads", "reported", "lost",
              "losing", "ended", "merged", "integrity");
  for (std::size_t b = 0; b < bins.size(); ++b) {
    const Tally& t = tallies[b];
    std::printf("%-40s %6d %6d %9lld %6lld %7d %7d %7d %9d\n", bins[b].c_str(), t.rounds, t.reads,
                static_cast<long long>(t.reported), static_cast<long long>(t.lost), t.rounds_losing, t.ended_by_reader,
                t.merges_accepted, t.integrity_failures);
  }
  std::printf("reported: trials the session reported completed; lost: of those, not in the file; losing: rounds "
              "that lost any; ended: sessions a reader ended before the kill; merged: merge --out onto the live "
              "file accepted; integrity: files failing PRAGMA integrity_check\n");
  fs::remove_all(dir);
  return 0;
}
