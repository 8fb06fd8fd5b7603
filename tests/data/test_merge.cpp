// Pooling a study: two simulated lab machines run headless sessions with the
// simulated observer (one session killed and resumed), `curvlab merge`
// pools them, and the pooled file, a second merge, conflicting copies,
// protocol versions and the exports are checked as a user would see them.
#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/merge.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include "data_files.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace fs = std::filesystem;
using namespace curvlab::harness::data;

using curvlab::testing::read_file;
using curvlab::testing::scalar;

namespace {

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("merge", name); }


const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

struct Cli {
  int exit_code = -1;
  std::string out;
};

Cli run_curvlab(const std::string& args) {
  Cli r;
  FILE* pipe = popen((std::string(CURVLAB_BIN) + " " + args + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buf{};
  for (std::size_t n; (n = fread(buf.data(), 1, buf.size(), pipe)) > 0;) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

// Removes this process's folders when the tests are done (machines() is
// shared by the tests of one process, so not before).
class RemoveFolders : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ec;
    const std::string suffix = "_" + std::to_string(::getpid());
    for (const auto& entry : fs::directory_iterator(fs::temp_directory_path(), ec)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("curvlab_merge_", 0) == 0 && name.size() > suffix.size() &&
          name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
        fs::remove_all(entry.path(), ec);
    }
  }
};
[[maybe_unused]] auto* const remove_folders = ::testing::AddGlobalTestEnvironment(new RemoveFolders);

std::int64_t count(const fs::path& db, const std::string& table) {
  return std::stoll(scalar(db, "SELECT COUNT(*) FROM " + table));
}

std::string run_args(const std::string& participant, const fs::path& db, const std::string& protocol = kDemo) {
  return "run " + protocol + " --participant " + participant + " --db " + db.string() + " --render none --quiet";
}

// Completed trials of `participant` in `db`, or -1 while it cannot be read.
std::int64_t completed_trials(const fs::path& db, const std::string& participant) {
  if (!fs::exists(db)) return -1;
  try {
    auto c = Connection::open(db.string(), OpenFlags::read_only);
    return c.query_int("SELECT COUNT(*) FROM trials t JOIN sessions s ON s.session_id = t.session_id JOIN "
                       "participants p ON p.participant_id = s.participant_id WHERE t.status = 'completed' "
                       "AND p.pseudonym = '" + participant + "'");
  } catch (const SqliteFailure&) {
    return -1;
  }
}

// Starts a realtime-paced session and kills it (SIGKILL) a little after its
// first trial is committed, inside the next trial: the file then holds a
// session that stopped mid-way, as after a crash.
void run_until_first_trial_then_kill(const std::string& participant, const fs::path& db) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    dup2(null, 1);
    dup2(null, 2);
    const std::string bin = CURVLAB_BIN, p = participant, d = db.string();
    execl(bin.c_str(), bin.c_str(), "run", kDemo.c_str(), "--participant", p.c_str(), "--db", d.c_str(),
          "--render", "none", "--pace", "realtime", "--quiet", static_cast<char*>(nullptr));
    _exit(127);
  }
  int status = 0;
  // No reader until the session has put the file in write-ahead-log mode:
  // before that a reader's lock can hold the writer up past its busy timeout
  // on a loaded machine, and the session would stop before it began.
  for (int i = 0; i < 3000 && !fs::exists(db.string() + "-wal"); ++i) {
    if (waitpid(pid, &status, WNOHANG) != 0) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  for (int i = 0; i < 3000 && completed_trials(db, participant) < 1; ++i) {
    if (waitpid(pid, &status, WNOHANG) != 0) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the ITI and fixation are 100 ms each
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
}

// Copies a database file with whatever write-ahead log it has, as a person
// copying a results folder would.
void copy_db(const fs::path& from, const fs::path& to) {
  for (const char* suffix : {"", "-wal"})
    if (fs::exists(from.string() + suffix))
      fs::copy_file(from.string() + suffix, to.string() + suffix, fs::copy_options::overwrite_existing);
}

// Two lab machines, built once for every test of this file.
struct Machines {
  fs::path dir, a, b, a_before_resume;
};

const Machines& machines() {
  static const Machines m = [] {
    Machines out;
    out.dir = fresh_dir("machines");
    out.a = out.dir / "lab_a.sqlite";
    out.b = out.dir / "lab_b.sqlite";
    out.a_before_resume = out.dir / "copies" / "lab_a_before_resume.sqlite";
    fs::create_directories(out.a_before_resume.parent_path());
    // Machine A: P01 completes; P02 is killed after a trial, copied, resumed.
    EXPECT_EQ(run_curvlab(run_args("P01", out.a)).exit_code, 0);
    run_until_first_trial_then_kill("P02", out.a);
    copy_db(out.a, out.a_before_resume);
    const std::string p02 = scalar(out.a, "SELECT s.session_id FROM sessions s JOIN participants p "
                                          "ON p.participant_id = s.participant_id WHERE p.pseudonym = 'P02'");
    const auto resumed = run_curvlab("resume --db " + out.a.string() + " --session " + p02 + " --render none --quiet");
    EXPECT_EQ(resumed.exit_code, 0) << resumed.out;
    // Machine B: P03, and another "first session" of P01.
    EXPECT_EQ(run_curvlab(run_args("P03", out.b)).exit_code, 0);
    EXPECT_EQ(run_curvlab(run_args("P01", out.b)).exit_code, 0);
    // P03's session as a headset with eye tracking would have stored it: a
    // gaze row for each of its frames (headless sessions record none).
    {
      auto c = Connection::open(out.b.string(), OpenFlags::read_write);
      c.exec("INSERT INTO gaze_samples (session_id, trial_id, frame_index, t_ns, left_valid, left_confidence, "
             "left_ox_m, left_oy_m, left_oz_m, left_dx, left_dy, left_dz, right_valid, right_confidence, right_ox_m, "
             "right_oy_m, right_oz_m, right_dx, right_dy, right_dz, vergence_rad, vergence_distance_m) "
             "SELECT f.session_id, f.trial_id, f.frame_index, f.frame_index * 11111111, 1, 0.9, -0.032, 1.6, 0, "
             "0.01, 0, -1, f.frame_index % 2, 0.7, 0.032, 1.6, 0, -0.01, 0, -1, 0.02, 3.2 FROM frames f "
             "JOIN sessions s ON s.session_id = f.session_id JOIN participants p ON "
             "p.participant_id = s.participant_id WHERE p.pseudonym = 'P03'");
    }
    return out;
  }();
  return m;
}

// Every value of `column` in `table`, quoted and sorted.
std::vector<std::string> column_values(const fs::path& db, const std::string& table, const std::string& column) {
  auto d = Database::open(db.string(), OpenMode::read_only);
  std::vector<std::string> values;
  Statement s(d.value().connection(), "SELECT quote(" + column + ") FROM " + table);
  while (s.step()) values.push_back(s.column_text(0));
  std::sort(values.begin(), values.end());
  return values;
}

// The columns of `table` other than ids, which a merge remaps.
std::vector<std::string> data_columns(const fs::path& db, const std::string& table) {
  auto d = Database::open(db.string(), OpenMode::read_only);
  std::vector<std::string> columns;
  Statement s(d.value().connection(), "SELECT name FROM pragma_table_info('" + table + "')");
  while (s.step()) {
    const std::string name = s.column_text(0);
    if (name.size() < 3 || name.substr(name.size() - 3) != "_id") columns.push_back(name);
  }
  return columns;
}

std::string uuid_of(const fs::path& db, const std::string& pseudonym) {
  return scalar(db, "SELECT s.session_uuid FROM sessions s JOIN participants p ON p.participant_id = "
                    "s.participant_id WHERE p.pseudonym = '" + pseudonym + "'");
}

}  // namespace

TEST(MergeCli, TwoMachinesPoolIntoOneStudyKeepingEveryRowAndItsProvenance) {
  const auto& m = machines();
  ASSERT_EQ(scalar(m.a, "SELECT status FROM sessions WHERE session_id = 2"), "completed");
  ASSERT_NE(scalar(m.a_before_resume, "SELECT status FROM sessions WHERE session_id = 2"), "completed")
      << "P02's session was not interrupted";
  ASSERT_LT(completed_trials(m.a_before_resume, "P02"), completed_trials(m.a, "P02"));
  const fs::path study = fresh_dir("pool") / "study.sqlite";
  const std::string b_bytes = read_file(m.b);
  const auto r = run_curvlab("merge --out " + study.string() + " " + m.a.string() + " " + m.b.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::cout << r.out;
  EXPECT_NE(r.out.find("total"), std::string::npos) << r.out;

  EXPECT_EQ(count(study, "sessions"), 4);
  ASSERT_GT(count(m.b, "gaze_samples"), 0);
  for (const char* table : {"trials", "blocks", "staircase_steps", "tracking_samples", "frames", "gaze_samples"})
    EXPECT_EQ(count(study, table), count(m.a, table) + count(m.b, table)) << table;
  // Every recorded event, plus one merged_from per session and one renumbering.
  EXPECT_EQ(count(study, "events"), count(m.a, "events") + count(m.b, "events") + 4 + 1);
  EXPECT_EQ(count(study, "protocols"), 1);
  EXPECT_EQ(count(study, "participants"), 3);
  EXPECT_EQ(scalar(study, "PRAGMA user_version"), std::to_string(current_schema_version));
  EXPECT_EQ(scalar(study, "PRAGMA integrity_check"), "ok");
  EXPECT_EQ(scalar(study, "SELECT COUNT(*) FROM pragma_foreign_key_check"), "0");

  // Every value of every column the schema has (so a column added later is
  // covered too) arrived, ids aside.
  for (const char* table : {"blocks", "trials", "staircase_steps", "tracking_samples", "frames", "gaze_samples"}) {
    for (const std::string& column : data_columns(study, table)) {
      auto expected = column_values(m.a, table, column);
      const auto from_b = column_values(m.b, table, column);
      expected.insert(expected.end(), from_b.begin(), from_b.end());
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(column_values(study, table, column), expected) << table << "." << column;
    }
  }
  // Each session's content is the same as in the file it came from, and
  // the file it came from is recorded.
  for (const auto& [file, who] : std::vector<std::pair<fs::path, std::string>>{
           {m.a, "P02"}, {m.b, "P03"}}) {
    const std::string uuid = uuid_of(file, who);
    const auto here = session_content_digest(study.string(), uuid);
    const auto there = session_content_digest(file.string(), uuid);
    ASSERT_TRUE(here && there);
    EXPECT_EQ(here.value(), there.value()) << who;
    EXPECT_EQ(scalar(study, "SELECT json_extract(e.detail, '$.source_file') FROM events e JOIN sessions s "
                            "ON s.session_id = e.session_id WHERE e.kind = 'merged_from' AND s.session_uuid = '" +
                                uuid + "'"),
              file.filename().string());
  }
  // B's P01 session clashed with A's session 1 of P01 and became session 2.
  const std::string b_p01 = uuid_of(m.b, "P01");
  EXPECT_EQ(scalar(study, "SELECT session_number FROM sessions WHERE session_uuid = '" + b_p01 + "'"), "2");
  EXPECT_EQ(scalar(study, "SELECT json_extract(detail, '$.from') || '->' || json_extract(detail, '$.to') "
                          "FROM events WHERE kind = 'session_renumbered'"),
            "1->2");
  // The resumed session's trials were run again in a second attempt and kept.
  EXPECT_EQ(scalar(study, "SELECT COUNT(*) FROM trials t JOIN sessions s ON s.session_id = t.session_id "
                          "WHERE s.session_uuid = '" + uuid_of(m.a, "P02") + "' AND t.status = 'completed'"),
            "8");
  // The inputs were not modified.
  EXPECT_EQ(read_file(m.b), b_bytes);
}

TEST(MergeCli, MergingAgainAddsNothingAndLeavesTheFileAsItWas) {
  const auto& m = machines();
  const fs::path study = fresh_dir("again") / "study.sqlite";
  ASSERT_EQ(run_curvlab("merge --out " + study.string() + " " + m.a.string()).exit_code, 0);
  // A second time, B added, and A given twice: only B's sessions are new.
  const auto r = run_curvlab("merge --out " + study.string() + " " + m.a.string() + " " + m.b.string() + " " +
                         m.a.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(count(study, "sessions"), 4);
  EXPECT_EQ(count(study, "trials"), count(m.a, "trials") + count(m.b, "trials"));
  const std::string before = read_file(study);
  const auto again = run_curvlab("merge --json --out " + study.string() + " " + m.dir.string());
  ASSERT_EQ(again.exit_code, 0) << again.out;
  EXPECT_NE(again.out.find("\"output_changed\": false"), std::string::npos) << again.out;
  EXPECT_NE(again.out.find("\"sessions_skipped\": 4"), std::string::npos) << again.out;
  EXPECT_EQ(read_file(study), before);
  // A merged file merged into a new study is the same study.
  const fs::path second = study.parent_path() / "second.sqlite";
  ASSERT_EQ(run_curvlab("merge --out " + second.string() + " " + study.string()).exit_code, 0);
  for (const char* who : {"P01", "P02", "P03"}) {
    const std::string uuid = uuid_of(m.a, who) == "NULL" ? uuid_of(m.b, who) : uuid_of(m.a, who);
    EXPECT_EQ(session_content_digest(second.string(), uuid).value(),
              session_content_digest(study.string(), uuid).value());
  }
}

TEST(MergeCli, SameSessionWithDifferentContentIsRefusedAndTheStudyIsUnchanged) {
  const auto& m = machines();
  const fs::path dir = fresh_dir("conflict");
  const fs::path study = dir / "study.sqlite";
  ASSERT_EQ(run_curvlab("merge --out " + study.string() + " " + m.a.string()).exit_code, 0);
  const std::string before = read_file(study);

  // A copy of machine A's file whose P01 responses were edited.
  const fs::path edited = dir / "edited.sqlite";
  copy_db(m.a, edited);
  {
    auto d = Database::open(edited.string(), OpenMode::open_existing);
    ASSERT_TRUE(d);
    d.value().connection().exec("UPDATE trials SET response = 'concave' WHERE session_id = 1 AND trial_index = 3");
  }
  const std::string p01 = uuid_of(m.a, "P01");
  const auto r = run_curvlab("merge --out " + study.string() + " " + m.b.string() + " " + edited.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(p01), std::string::npos) << r.out;
  EXPECT_EQ(read_file(study), before);
  EXPECT_EQ(count(study, "sessions"), 2) << "machine B's sessions were added despite the conflict";
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().string().find(".merging-"), std::string::npos) << entry.path();

  // The copy of machine A's file taken before P02's session was resumed.
  const auto early = run_curvlab("merge --out " + study.string() + " " + m.a_before_resume.string());
  EXPECT_EQ(early.exit_code, 2) << early.out;
  EXPECT_NE(early.out.find(uuid_of(m.a, "P02")), std::string::npos) << early.out;
  EXPECT_NE(early.out.find("merge only the later file"), std::string::npos) << early.out;
  EXPECT_EQ(read_file(study), before);
}

TEST(MergeCli, ProtocolVersionsUnderOneNameNeedTheFlag) {
  const auto& m = machines();
  const fs::path dir = fresh_dir("versions");
  // Machine C ran an edited demo: same name, other text.
  std::string text = read_file(kDemo);
  text.replace(text.find("stimulus_ms = 300"), 17, "stimulus_ms = 400");
  const fs::path protocol = dir / "demo.toml";
  std::ofstream(protocol) << text;
  fs::copy_file(fs::path(kDemo).parent_path() / "schema.json", dir / "schema.json");
  const fs::path c = dir / "lab_c.sqlite";
  const auto ran = run_curvlab(run_args("P04", c, protocol.string()));
  ASSERT_EQ(ran.exit_code, 0) << ran.out;

  const fs::path study = dir / "study.sqlite";
  const auto refused = run_curvlab("merge --out " + study.string() + " " + m.a.string() + " " + c.string());
  EXPECT_EQ(refused.exit_code, 2) << refused.out;
  EXPECT_NE(refused.out.find("--allow-protocol-versions"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(study));

  const auto allowed = run_curvlab("merge --allow-protocol-versions --out " + study.string() + " " + m.a.string() +
                               " " + c.string());
  ASSERT_EQ(allowed.exit_code, 0) << allowed.out;
  EXPECT_EQ(count(study, "protocols"), 2);
  EXPECT_EQ(scalar(study, "SELECT pr.sha256 FROM sessions s JOIN protocols pr ON pr.protocol_id = s.protocol_id "
                          "WHERE s.session_uuid = '" + uuid_of(c, "P04") + "'"),
            scalar(c, "SELECT sha256 FROM protocols"));
}

TEST(MergeCli, ExportOfSeparateFilesEqualsExportOfTheMergedFile) {
  const auto& m = machines();
  const fs::path dir = fresh_dir("export");
  const fs::path study = dir / "study.sqlite";
  ASSERT_EQ(run_curvlab("merge --out " + study.string() + " " + m.a.string() + " " + m.b.string()).exit_code, 0);
  const auto sep = run_curvlab("export --db " + m.a.string() + " " + m.b.string() + " --out " + (dir / "separate").string());
  ASSERT_EQ(sep.exit_code, 0) << sep.out;
  const auto merged = run_curvlab("export --db " + study.string() + " --out " + (dir / "merged").string());
  ASSERT_EQ(merged.exit_code, 0) << merged.out;
  const std::string csv = read_file(dir / "separate" / "trials.csv");
  EXPECT_EQ(csv, read_file(dir / "merged" / "trials.csv"));
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + count(study, "trials"));
  EXPECT_EQ(csv.rfind("session_id,session_uuid,", 0), 0u) << csv.substr(0, 80);
  // Every data file of the other formats is the same too.
  std::size_t compared = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir / "merged")) {
    const fs::path rel = fs::relative(entry.path(), dir / "merged");
    if (!entry.is_regular_file() || rel.filename() == "dataset_description.json") continue;
    EXPECT_EQ(read_file(entry.path()), read_file(dir / "separate" / rel)) << rel;
    ++compared;
  }
  EXPECT_GT(compared, 10u);
  // A folder of files gives the same rows as listing them.
  const auto folder = run_curvlab("export --format csv --db " + m.dir.string() + " --out " + (dir / "folder").string());
  ASSERT_EQ(folder.exit_code, 0) << folder.out;
  EXPECT_EQ(read_file(dir / "folder" / "trials.csv"), csv);
}

TEST(MergeCli, OlderForeignOrMissingInputsAreRefusedWithoutBeingTouched) {
  const fs::path dir = fresh_dir("refuse");
  const fs::path foreign = dir / "other.sqlite";
  {
    auto c = Connection::open(foreign.string(), OpenFlags::read_write_create);
    c.exec("CREATE TABLE t (x); INSERT INTO t VALUES (1); PRAGMA user_version = 3");
  }
  const std::string before = read_file(foreign);
  const auto r = run_curvlab("merge --out " + (dir / "study.sqlite").string() + " " + foreign.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("not a curvlab data file"), std::string::npos) << r.out;
  EXPECT_EQ(read_file(foreign), before);
  EXPECT_FALSE(fs::exists(dir / "study.sqlite"));

  // A version-3 file (before session UUIDs): refused with the upgrade
  // command, and left as it was.
  const fs::path v3 = dir / "v3.sqlite";
  {
    auto c = Connection::open(v3.string(), OpenFlags::read_write_create);
    c.exec(read_file(fs::path(CURVLAB_SOURCE_DIR) / "data_schema" / "v3.sql"));
    c.exec("PRAGMA application_id = " + std::to_string(curvlab_application_id));
  }
  const std::string v3_before = read_file(v3);
  const auto old = run_curvlab("merge --out " + (dir / "study.sqlite").string() + " " + v3.string());
  EXPECT_EQ(old.exit_code, 2) << old.out;
  EXPECT_NE(old.out.find("schema version 3"), std::string::npos) << old.out;
  EXPECT_NE(old.out.find("curvlab upgrade --db " + v3.string()), std::string::npos) << old.out;
  EXPECT_EQ(read_file(v3), v3_before);
  EXPECT_FALSE(fs::exists(dir / "study.sqlite"));
  // The command the message names upgrades it, and the merge then goes through.
  const auto upgraded = run_curvlab("upgrade --db " + v3.string());
  EXPECT_EQ(upgraded.exit_code, 0) << upgraded.out;
  EXPECT_EQ(run_curvlab("merge --out " + (dir / "study.sqlite").string() + " " + v3.string()).exit_code, 0);
  fs::remove(dir / "study.sqlite");
  const auto missing = run_curvlab("merge --out " + (dir / "study.sqlite").string() + " " + (dir / "nope.sqlite").string());
  EXPECT_EQ(missing.exit_code, 2) << missing.out;
  EXPECT_NE(missing.out.find("nope.sqlite: no such database file"), std::string::npos) << missing.out;
}
