// What a data file and its exports reveal about the people of a lab: no
// folder of the machine they ran on (a home folder carries a name), and no
// pseudonym that is a name with a birth date, an e-mail address or an
// option. docs/data.md, "Privacy", lists the rules.
#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/session_store.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include "../cli/run_cli.hpp"
#include "data_files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace curvlab::harness::data;
using curvlab::testing::run_cli;

using curvlab::testing::read_file;
using curvlab::testing::scalar;

namespace {

fs::path fresh_dir(const std::string& name) { return curvlab::testing::fresh_test_dir("privacy", name); }


const std::string kDemo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";

void run_session(const fs::path& db, const std::string& pseudonym) {
  const auto r = run_cli("run " + kDemo + " --participant " + pseudonym + " --db " + db.string() +
                         " --render none --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.out;
}

}  // namespace

TEST(Privacy, PseudonymsInUseStayValid) {
  for (const char* ok : {"P01", "P-01", "P_01", "SIM1", "S-003", "pilot_2", "pilot1", "X01", "T1", "F01", "P1",
                         "P2024", "S01-2024", "P01-2024-13", "0123456789", "A1234567890123456789012345678901"})
    EXPECT_TRUE(valid_pseudonym(ok)) << ok;
}

TEST(Privacy, PseudonymsWithADateAnEmailOrALeadingDashAreRefused) {
  for (const char* bad : {"John_Smith_1985-03-14", "js_14-03-1985", "js_03_14_1985", "JS19850314", "P14031985",
                          "1985_3_14", "2024-12-31_P01", "--help", "-P01", "jane@example.org", "Jane Doe", "",
                          "A12345678901234567890123456789012"})
    EXPECT_FALSE(valid_pseudonym(bad)) << bad;

  // The store refuses them with the reason.
  const auto dir = fresh_dir("pseudonyms");
  auto db = Database::open((dir / "s.sqlite").string(), OpenMode::create_or_open);
  ASSERT_TRUE(db);
  SessionStore store(std::move(db).value());
  const std::pair<const char*, const char*> reasons[] = {
      {"John_Smith_1985-03-14", "the date 1985-03-14"},
      {"--help", "begins with '-'"},
      {"jane@example.org", "'@'"},
  };
  for (const auto& [pseudonym, reason] : reasons) {
    const auto added = store.add_participant({pseudonym, std::nullopt, DominantEye::unknown});
    ASSERT_FALSE(added) << pseudonym;
    EXPECT_EQ(added.error().kind, DataError::Kind::bad_input);
    EXPECT_NE(added.error().message.find(reason), std::string::npos) << added.error().message;
  }
}

TEST(CliPrivacy, ADatedPseudonymIsRefusedBeforeAFileIsCreated) {
  const auto dir = fresh_dir("dated");
  const auto r = run_cli("run " + kDemo + " --participant John_Smith_1985-03-14 --db " + (dir / "s.sqlite").string() +
                         " --render none --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--participant"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir / "s.sqlite"));
}

TEST(CliPrivacy, TheStoredProtocolSourceIsItsFileNameAlone) {
  const auto dir = fresh_dir("source");
  ASSERT_TRUE(fs::path(kDemo).is_absolute());
  run_session(dir / "a.sqlite", "P01");
  EXPECT_EQ(scalar(dir / "a.sqlite", "SELECT group_concat(source_path) FROM protocols"), "demo.toml");
}

TEST(CliPrivacy, MergeCarriesFileNamesNotFolders) {
  const auto dir = fresh_dir("merge");
  run_session(dir / "a.sqlite", "P01");
  // As a file written before only file names were stored.
  {
    auto db = Database::open((dir / "a.sqlite").string(), OpenMode::open_existing);
    ASSERT_TRUE(db);
    db.value().connection().exec("UPDATE protocols SET source_path = '/home/jane.doe/study/demo.toml'");
  }
  const auto r = run_cli("merge --out " + (dir / "study.sqlite").string() + " " + (dir / "a.sqlite").string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(scalar(dir / "study.sqlite", "SELECT group_concat(source_path) FROM protocols"), "demo.toml");
  EXPECT_EQ(scalar(dir / "study.sqlite",
                   "SELECT group_concat(json_extract(detail, '$.source_file')) FROM events WHERE kind = 'merged_from'"),
            "a.sqlite");
  // No event names the folder the file was in.
  EXPECT_EQ(scalar(dir / "study.sqlite", "SELECT count(*) FROM events WHERE instr(detail, '" + dir.string() +
                                             "') OR instr(detail, 'jane.doe')"),
            "0");
}

TEST(CliPrivacy, ExportDescriptionsNameFilesNotFolders) {
  const auto dir = fresh_dir("describe");
  run_session(dir / "a.sqlite", "P01");
  run_session(dir / "b.sqlite", "P02");
  const auto pooled = run_cli("export --db " + (dir / "a.sqlite").string() + " " + (dir / "b.sqlite").string() +
                              " --out " + (dir / "pooled").string());
  ASSERT_EQ(pooled.exit_code, 0) << pooled.out;
  const auto single = run_cli("export --db " + (dir / "a.sqlite").string() + " --out " + (dir / "single").string());
  ASSERT_EQ(single.exit_code, 0) << single.out;
  for (const char* out : {"pooled", "single"}) {
    const std::string description = read_file(dir / out / "psychds" / "dataset_description.json");
    EXPECT_NE(description.find("a.sqlite"), std::string::npos) << description;
    EXPECT_EQ(description.find(dir.string()), std::string::npos) << description;
    EXPECT_EQ(description.find(fs::temp_directory_path().string() + "/"), std::string::npos) << description;
    for (const auto& e : fs::recursive_directory_iterator(dir / out)) {
      if (!e.is_regular_file()) continue;
      EXPECT_EQ(read_file(e.path()).find(dir.string()), std::string::npos) << e.path();
    }
  }
}
