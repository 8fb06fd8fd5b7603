// What `curvlab export`, `merge` and `run` leave on disk, as a user finds it:
// participants whose labels would collide are refused before anything is
// written, the reported row counts are the rows in the files, a failing
// export leaves no half-written tree, leftovers of killed processes are
// removed on the next run, and misplaced --images and --db arguments are
// refused before anything is created.
#include "../cli/run_cli.hpp"
#include "data_files.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using curvlab::testing::run_cli;

using curvlab::testing::read_file;
using curvlab::testing::scalar;

namespace {

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("files", name); }


const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

// One completed headless session of protocols/demo.toml per pseudonym.
void run_sessions(const fs::path& db, const std::vector<std::string>& pseudonyms) {
  for (const auto& p : pseudonyms) {
    const auto r = run_cli("run " + kDemo + " --participant " + p + " --db " + db.string() +
                           " --render none --quiet --new-session");
    ASSERT_EQ(r.exit_code, 0) << p << ":\n" << r.out;
  }
}

std::size_t line_count(const std::string& text) {
  std::size_t n = 0;
  for (char c : text) n += c == '\n';
  return n;
}

// Every file and folder under `root`: relative path → hash of the content.
std::map<std::string, std::string> tree(const fs::path& root) {
  std::map<std::string, std::string> out;
  if (!fs::exists(root)) return out;
  for (const auto& e : fs::recursive_directory_iterator(root))
    out[fs::relative(e.path(), root).string()] =
        e.is_regular_file() ? std::to_string(std::hash<std::string>{}(read_file(e.path()))) : "folder";
  return out;
}

// A process id that no longer exists: a child that has exited and been reaped.
pid_t dead_pid() {
  const pid_t pid = fork();
  if (pid == 0) _exit(0);
  int status = 0;
  waitpid(pid, &status, 0);
  return pid;
}

void touch(const fs::path& p, const std::string& content = "leftover") { std::ofstream(p) << content; }

// Runs `prefix` curvlab `args` through the shell, as run_cli does: for an
// environment variable or a resource limit in front of the command.
curvlab::testing::CliResult run_cli_with(const std::string& prefix, const std::string& args) {
  curvlab::testing::CliResult r;
  FILE* pipe = popen((prefix + " " + CURVLAB_BIN + " " + args + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  char buf[4096];
  for (std::size_t n; (n = fread(buf, 1, sizeof buf, pipe)) > 0;) r.out.append(buf, n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace

TEST(CliExportLabels, ParticipantsSharingALabelAreRefusedAndNothingIsWritten) {
  const auto dir = fresh_dir("labels");
  run_sessions(dir / "s.sqlite", {"P01", "P-01", "P_01"});
  for (const char* format : {"all", "psychds", "bids-motion"}) {
    const fs::path out = dir / (std::string("out-") + format);
    const auto r = run_cli("export --db " + (dir / "s.sqlite").string() + " --out " + out.string() + " --format " +
                           format);
    EXPECT_EQ(r.exit_code, 2) << format << ":\n" << r.out;
    for (const char* named : {"\"P01\"", "\"P-01\"", "\"P_01\"", "label \"P01\""})
      EXPECT_NE(r.out.find(named), std::string::npos) << format << " does not name " << named << ":\n" << r.out;
    EXPECT_FALSE(fs::exists(out)) << format << ": something was written";
  }
  // Labels that differ only in case name one file on a disk that ignores case.
  run_sessions(dir / "case.sqlite", {"p01", "P01"});
  const auto cased = run_cli("export --db " + (dir / "case.sqlite").string() + " --out " +
                             (dir / "out-case").string() + " --format bids-motion");
  EXPECT_EQ(cased.exit_code, 2) << cased.out;
  EXPECT_NE(cased.out.find("ignores case"), std::string::npos) << cased.out;
  EXPECT_FALSE(fs::exists(dir / "out-case"));
  // The trial CSV names no file after a participant: it is written whole.
  const fs::path out = dir / "out-csv";
  const auto r = run_cli("export --db " + (dir / "s.sqlite").string() + " --out " + out.string() +
                         " --format csv --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(line_count(read_file(out / "trials.csv")) - 1, 3u * 8u);
}

TEST(CliExportLabels, ProtocolNamesSharingALabelAreRefused) {
  const auto dir = fresh_dir("protocol_labels");
  // Two protocols whose names differ only in '-' against '_'.
  const std::string text = read_file(kDemo);
  for (const char* name : {"my-task", "my_task"}) {
    std::string copy = text;
    const auto at = copy.find("name = \"demo\"");
    ASSERT_NE(at, std::string::npos);
    copy.replace(at, 13, std::string("name = \"") + name + "\"");
    std::ofstream(dir / (std::string(name) + ".toml")) << copy;
    const auto r = run_cli("run " + (dir / (std::string(name) + ".toml")).string() + " --participant P01 --db " +
                           (dir / "s.sqlite").string() + " --render none --quiet --new-session");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  }
  const auto r = run_cli("export --db " + (dir / "s.sqlite").string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  for (const char* named : {"\"my-task\"", "\"my_task\"", "label \"mytask\""})
    EXPECT_NE(r.out.find(named), std::string::npos) << named << ":\n" << r.out;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(CliExportCounts, ReportedRowsAreTheRowsInTheFiles) {
  const auto dir = fresh_dir("counts");
  run_sessions(dir / "s.sqlite", {"P01", "P02", "P01"});
  const fs::path out = dir / "out";
  const auto r = run_cli("export --db " + (dir / "s.sqlite").string() + " --out " + out.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = nlohmann::json::parse(r.out);
  std::set<std::string> listed;
  std::size_t psychds_rows = 0, motion_rows = 0;
  for (const auto& f : doc["files"]) {
    const std::string name = f.get<std::string>();
    EXPECT_TRUE(listed.insert(name).second) << name << " is listed twice";
    ASSERT_TRUE(fs::is_regular_file(out / name)) << name;
    if (name.rfind("psychds/data/", 0) == 0) psychds_rows += line_count(read_file(out / name)) - 1;
    if (name.size() > 11 && name.compare(name.size() - 11, 11, "_motion.tsv") == 0)
      motion_rows += line_count(read_file(out / name));
  }
  EXPECT_EQ(line_count(read_file(out / "trials.csv")) - 1, doc["csv_rows"].get<std::size_t>());
  EXPECT_EQ(doc["csv_rows"].get<std::size_t>(), 3u * 8u);
  EXPECT_EQ(psychds_rows, doc["psychds_rows"].get<std::size_t>());
  EXPECT_EQ(motion_rows, doc["bids-motion_rows"].get<std::size_t>());
  EXPECT_GT(motion_rows, 0u);
  // And every file written is listed.
  std::size_t on_disk = 0;
  for (const auto& e : fs::recursive_directory_iterator(out)) on_disk += e.is_regular_file();
  EXPECT_EQ(on_disk, listed.size());
}

TEST(CliExportStaging, AFailedExportLeavesNoPartialTreeAndKeepsWhatWasThere) {
  const auto dir = fresh_dir("staging");
  run_sessions(dir / "one.sqlite", {"P01"});
  run_sessions(dir / "two.sqlite", {"P01", "P02"});
  const fs::path out = dir / "out";
  ASSERT_EQ(run_cli("export --db " + (dir / "one.sqlite").string() + " --out " + out.string()).exit_code, 0);
  const auto before = tree(out);
  // A file may not grow past 40000 bytes, as on a full disk: the first
  // motion file (about 50 kB) fails to be written (EFBIG, with SIGXFSZ
  // ignored so that write() reports it).
  auto limited = [&](const fs::path& db, const fs::path& to, const std::string& format) {
    return run_cli_with("trap '' XFSZ; prlimit --fsize=40000",
                        "export --db " + db.string() + " --out " + to.string() + " --format " + format);
  };
  const auto r = limited(dir / "two.sqlite", out, "bids-motion");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("_motion.tsv"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("failed"), std::string::npos) << r.out;
  EXPECT_EQ(tree(out), before) << "the earlier export was changed:\n" << r.out;

  // Into a folder that did not exist: nothing remains, not even the folder.
  const fs::path fresh = dir / "fresh";
  const auto again = limited(dir / "one.sqlite", fresh, "bids-motion");
  EXPECT_EQ(again.exit_code, 1) << again.out;
  EXPECT_FALSE(fs::exists(fresh)) << "left behind:\n" << [&] {
    std::string s;
    for (const auto& [name, _] : tree(fresh)) s += name + "\n";
    return s;
  }();

  // A complete export replaces each format's part whole: nothing of the
  // earlier, smaller export is mixed in, and other files are left alone.
  touch(out / "notes.txt", "mine");
  ASSERT_EQ(run_cli("export --db " + (dir / "two.sqlite").string() + " --out " + out.string()).exit_code, 0);
  EXPECT_TRUE(fs::exists(out / "bids" / "sub-P02"));
  EXPECT_EQ(read_file(out / "notes.txt"), "mine");
  for (const auto& [name, _] : tree(out)) EXPECT_EQ(name.find(".partial-"), std::string::npos) << name;
}

TEST(CliStaleStaging, MergeAndExportRemoveLeftoversOfProcessesThatAreGone) {
  const auto dir = fresh_dir("stale");
  run_sessions(dir / "a.sqlite", {"P01"});
  run_sessions(dir / "b.sqlite", {"P02"});
  const std::string dead = std::to_string(dead_pid());
  const std::string alive = std::to_string(::getpid());

  // merge stages into OUT.merging-PID beside the output.
  const fs::path study = dir / "study.sqlite";
  for (const auto& suffix : {dead, dead + "-journal", alive}) touch(dir / ("study.sqlite.merging-" + suffix));
  const auto m = run_cli("merge --out " + study.string() + " " + (dir / "a.sqlite").string());
  ASSERT_EQ(m.exit_code, 0) << m.out;
  EXPECT_FALSE(fs::exists(dir / ("study.sqlite.merging-" + dead)));
  EXPECT_FALSE(fs::exists(dir / ("study.sqlite.merging-" + dead + "-journal")));
  EXPECT_TRUE(fs::exists(dir / ("study.sqlite.merging-" + alive))) << "a running merge's file was removed";

  // A pooled export stages into $TMPDIR/curvlab-export-PID.sqlite, each
  // format into a sibling of its part of the out folder.
  const fs::path tmp = dir / "tmp";
  const fs::path out = dir / "out";
  fs::create_directories(tmp);
  fs::create_directories(out / ("bids.partial-" + dead) / "sub-P01");
  fs::create_directories(out / ("bids.partial-" + alive));
  for (const auto& suffix : {dead + ".sqlite", dead + ".sqlite-wal", dead + ".sqlite.merging-" + dead,
                             alive + ".sqlite"})
    touch(tmp / ("curvlab-export-" + suffix));
  touch(tmp / "curvlab-export-notes.txt");
  const auto r = run_cli_with("TMPDIR=" + tmp.string(), "export --db " + (dir / "a.sqlite").string() + " " +
                                                           (dir / "b.sqlite").string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::set<std::string> left;
  for (const auto& entry : fs::directory_iterator(tmp)) left.insert(entry.path().filename().string());
  EXPECT_EQ(left, (std::set<std::string>{"curvlab-export-" + alive + ".sqlite", "curvlab-export-notes.txt"}));
  EXPECT_FALSE(fs::exists(out / ("bids.partial-" + dead)));
  EXPECT_TRUE(fs::exists(out / ("bids.partial-" + alive))) << "a running export's folder was removed";
}

TEST(CliRunArguments, ImagesFileAndDbFolderExitTwoBeforeAnythingIsCreated) {
  const auto dir = fresh_dir("run_args");
  touch(dir / "picture.png", "not a folder");
  const auto images = run_cli("run " + kDemo + " --participant P01 --db " + (dir / "s.sqlite").string() +
                              " --render none --quiet --images " + (dir / "picture.png").string());
  EXPECT_EQ(images.exit_code, 2) << images.out;
  EXPECT_NE(images.out.find("--images"), std::string::npos) << images.out;
  EXPECT_NE(images.out.find("folder"), std::string::npos) << images.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
  EXPECT_EQ(read_file(dir / "picture.png"), "not a folder");

  fs::create_directories(dir / "results");
  const auto db = run_cli("run " + kDemo + " --participant P01 --db " + (dir / "results").string() +
                          " --render none --quiet");
  EXPECT_EQ(db.exit_code, 2) << db.out;
  EXPECT_NE(db.out.find("--db"), std::string::npos) << db.out;
  EXPECT_NE(db.out.find("database file"), std::string::npos) << db.out;
  EXPECT_TRUE(fs::is_empty(dir / "results"));
}
