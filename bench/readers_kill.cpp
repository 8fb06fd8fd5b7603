// Readers during a session, then kill -9: the way a lab lost trials. Each
// round starts a realtime demo session, lets curvlab export, the sqlite3
// shell and Python's sqlite3 open and close the file in turn, kills the
// session at a random instant and compares the trials it reported completed
// with the trials stored. Usage:
//   bench_readers_kill [ROUNDS] [CURVLAB ...]
// Several executables (an older build beside this one) are measured in the
// same run, round for round on the same kill instants.
#include "curvlab/harness/data/database.hpp"
#include "sharing_support.hpp"

#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>


namespace fs = std::filesystem;
namespace sh = curvlab::testing::sharing;
using curvlab::data::Connection;
using curvlab::data::OpenFlags;

namespace {

struct Tally {
  int rounds = 0;
  int rounds_losing = 0;
  std::int64_t reported = 0;
  std::int64_t lost = 0;
  int reads = 0;
};

std::int64_t stored_completed(const std::string& db) {
  try {
    auto c = Connection::open(db, OpenFlags::read_only);
    return c.query_int("SELECT count(*) FROM trials WHERE status = 'completed'");
  } catch (const std::exception&) {
    return 0;
  }
}

void round(const std::string& bin, const fs::path& dir, int k, int kill_after_ms, Tally& t) {
  std::string name = "r";
  name += std::to_string(k);
  name += ".sqlite";
  const std::string db = (dir / name).string();
  curvlab::data::remove_database_files(db);
  sh::Child run = sh::spawn(bin,
                            {"run", std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml", "--participant", "P01",
                             "--db", db, "--render", "none", "--pace", "realtime", "--progress", "json"},
                            dir / "run.out", dir / "run.err");
  if (!sh::wait_for_lines(run.out, "\"status\":\"completed\"", 1, std::chrono::seconds(60))) return;
  const auto stop_at = std::chrono::steady_clock::now() + std::chrono::milliseconds(kill_after_ms);
  for (int r = 0; std::chrono::steady_clock::now() < stop_at; ++r, ++t.reads) sh::read_once(bin, db, dir, r);
  run.kill9();
  const std::int64_t reported = sh::count_lines(run.out, "\"status\":\"completed\"");
  const std::int64_t stored = stored_completed(db);
  ++t.rounds;
  t.reported += reported;
  if (stored < reported) {
    ++t.rounds_losing;
    t.lost += reported - stored;
  }
  curvlab::data::remove_database_files(db);
  fs::remove(db + ".lock");
}

}  // namespace

int main(int argc, char** argv) {
  const int rounds = argc > 1 ? std::atoi(argv[1]) : 50;
  std::vector<std::string> bins;
  for (int i = 2; i < argc; ++i) bins.emplace_back(argv[i]);
  if (bins.empty()) bins.push_back((fs::path(argv[0]).parent_path() / "curvlab").string());
  const fs::path dir = fs::temp_directory_path() / ("curvlab_bench_readers_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::vector<Tally> tallies(bins.size());
  std::mt19937 rng(20261125);
  for (int k = 0; k < rounds; ++k) {
    const int kill_after_ms = std::uniform_int_distribution<int>(1500, 4500)(rng);
    for (std::size_t b = 0; b < bins.size(); ++b) round(bins[b], dir, k, kill_after_ms, tallies[b]);
    std::fprintf(stderr, "\rround %d/%d", k + 1, rounds);
  }
  std::fprintf(stderr, "\n");
  std::printf("%-48s %7s %8s %14s %10s %14s\n", "curvlab", "rounds", "reads", "trials_reported", "trials_lost",
              "rounds_losing");
  for (std::size_t b = 0; b < bins.size(); ++b)
    std::printf("%-48s %7d %8d %14lld %10lld %14d\n", bins[b].c_str(), tallies[b].rounds, tallies[b].reads,
                static_cast<long long>(tallies[b].reported), static_cast<long long>(tallies[b].lost),
                tallies[b].rounds_losing);
  fs::remove_all(dir);
  return 0;
}
