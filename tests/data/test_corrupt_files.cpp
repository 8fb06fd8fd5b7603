// Damaged and foreign files: random bytes, a curvlab file cut off mid-way and
// another program's SQLite database are refused by the data layer before
// anything is written, and every command that takes --db exits 2 with one
// message saying whether the file can be read and how to recover it.
#include "curvlab/harness/data/database.hpp"

#include "../cli/run_cli.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

using namespace curvlab::harness::data;
namespace fs = std::filesystem;

namespace {

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("curvlab_corrupt_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

struct BadFile {
  std::string label;
  fs::path path;
  DataError::Kind kind;
  std::string says;  // a phrase the message must contain
};

// The three kinds of bad file the commands must refuse.
std::vector<BadFile> make_bad_files(const fs::path& dir) {
  std::vector<BadFile> files;
  {
    std::mt19937 rng(20261124);
    std::string bytes(64 * 1024, '\0');
    for (char& b : bytes) b = static_cast<char>(rng() & 0xFF);
    write_bytes(dir / "random.sqlite", bytes);
    files.push_back({"random bytes", dir / "random.sqlite", DataError::Kind::not_curvlab,
                     "cannot be read at all"});
  }
  {
    const fs::path whole = dir / "whole.sqlite";
    {
      auto db = Database::open(whole.string(), OpenMode::create_or_open);
      EXPECT_TRUE(db) << db.error().message;
    }
    const std::string bytes = read_bytes(whole);
    EXPECT_GT(bytes.size(), 8u * 4096u) << "the schema alone should span several pages";
    EXPECT_FALSE(fs::exists(whole.string() + "-wal"));
    // Cut off mid-way, inside a page, as an interrupted copy leaves it.
    write_bytes(dir / "truncated.sqlite", bytes.substr(0, bytes.size() / 2 + 1000));
    files.push_back({"truncated curvlab file", dir / "truncated.sqlite", DataError::Kind::corrupt,
                     "only part of it can be read"});
  }
  {
    auto other = Connection::open((dir / "foreign.sqlite").string(), OpenFlags::read_write_create);
    other.exec("CREATE TABLE photos (id INTEGER PRIMARY KEY, path TEXT); INSERT INTO photos VALUES (1, 'a.jpg')");
  }
  files.push_back({"foreign SQLite database", dir / "foreign.sqlite", DataError::Kind::not_curvlab,
                   "a readable SQLite database written by another program"});
  return files;
}

}  // namespace

TEST(CorruptFiles, DatabaseOpenRefusesEachKindInEveryModeAndLeavesItAlone) {
  const auto dir = fresh_dir("open");
  for (const auto& f : make_bad_files(dir)) {
    const std::string before = read_bytes(f.path);
    for (const auto mode : {OpenMode::create_or_open, OpenMode::open_existing, OpenMode::read_only}) {
      auto db = Database::open(f.path.string(), mode);
      ASSERT_FALSE(db) << f.label;
      EXPECT_EQ(db.error().kind, f.kind) << f.label << ": " << db.error().message;
      EXPECT_EQ(curvlab::harness::exit_code(db.error()), 2) << f.label;
      EXPECT_EQ(db.error().message.rfind(f.path.string() + ": ", 0), 0u) << db.error().message;
      EXPECT_NE(db.error().message.find(f.says), std::string::npos) << db.error().message;
      const bool recoverable = f.kind == DataError::Kind::corrupt || f.label == "random bytes";
      EXPECT_EQ(db.error().message.find("sqlite3 " + f.path.string() + " .recover | sqlite3 recovered.sqlite") !=
                    std::string::npos,
                recoverable)
          << db.error().message;
    }
    EXPECT_EQ(read_bytes(f.path), before) << f.label << " was modified";
    EXPECT_FALSE(fs::exists(f.path.string() + "-wal")) << f.label;
  }
}

TEST(CorruptFiles, TruncationIsMeasuredAgainstTheHeader) {
  const auto dir = fresh_dir("header");
  const fs::path whole = dir / "whole.sqlite";
  { ASSERT_TRUE(Database::open(whole.string(), OpenMode::create_or_open)); }
  EXPECT_TRUE(check_data_file(whole.string()));
  const std::string bytes = read_bytes(whole);
  write_bytes(dir / "short_header.sqlite", bytes.substr(0, 60));
  auto short_header = check_data_file((dir / "short_header.sqlite").string());
  ASSERT_FALSE(short_header);
  EXPECT_EQ(short_header.error().kind, DataError::Kind::corrupt);
  EXPECT_NE(short_header.error().message.find("shorter than the 100-byte SQLite header"), std::string::npos);
  write_bytes(dir / "one_page_short.sqlite", bytes.substr(0, bytes.size() - 4096));
  auto one_page = check_data_file((dir / "one_page_short.sqlite").string());
  ASSERT_FALSE(one_page);
  EXPECT_NE(one_page.error().message.find("truncated to " + std::to_string(bytes.size() - 4096) + " bytes"),
            std::string::npos)
      << one_page.error().message;
  // Missing and empty files are not damaged: sessions create them.
  EXPECT_TRUE(check_data_file((dir / "absent.sqlite").string()));
  write_bytes(dir / "empty.sqlite", "");
  EXPECT_TRUE(check_data_file((dir / "empty.sqlite").string()));
  // A path with a space is quoted in the suggested command.
  write_bytes(dir / "my data.sqlite", "not sqlite at all, just text");
  auto spaced = check_data_file((dir / "my data.sqlite").string());
  ASSERT_FALSE(spaced);
  EXPECT_NE(spaced.error().message.find("sqlite3 '" + (dir / "my data.sqlite").string() + "' .recover"),
            std::string::npos)
      << spaced.error().message;
}

TEST(CorruptFiles, DamageInsideTheFileIsCorruptWithTheRecoverHint) {
  const auto dir = fresh_dir("inside");
  const fs::path path = dir / "overwritten.sqlite";
  { ASSERT_TRUE(Database::open(path.string(), OpenMode::create_or_open)); }
  std::string bytes = read_bytes(path);
  // Page 1 (header and schema root) intact, every other page zeroed in its
  // b-tree header: the size matches, the content does not.
  for (std::size_t page = 4096; page < bytes.size(); page += 4096) bytes.replace(page, 16, std::string(16, '\xff'));
  write_bytes(path, bytes);
  EXPECT_TRUE(check_data_file(path.string()));
  auto opened = Database::open(path.string(), OpenMode::open_existing);
  std::string message;
  if (!opened) {
    EXPECT_EQ(opened.error().kind, DataError::Kind::corrupt) << opened.error().message;
    message = opened.error().message;
  } else {
    try {
      Statement(opened.value().connection(), "SELECT count(*) FROM trials").step();
      FAIL() << "reading a zeroed page succeeded";
    } catch (const SqliteFailure& f) {
      const DataError e = to_data_error(f, path.string());
      EXPECT_EQ(e.kind, DataError::Kind::corrupt) << e.message;
      message = e.message;
    }
  }
  EXPECT_NE(message.find("damaged curvlab data file"), std::string::npos) << message;
  EXPECT_NE(message.find(".recover | sqlite3 recovered.sqlite"), std::string::npos) << message;
}

TEST(CliCorruptFiles, EveryCommandTakingADatabaseExitsTwoWithOneMessage) {
  using curvlab::testing::run_cli;
  const auto dir = fresh_dir("cli");
  const std::string demo = std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml";
  for (const auto& f : make_bad_files(dir)) {
    const std::string db = f.path.string();
    const std::string before = read_bytes(f.path);
    const std::vector<std::pair<std::string, std::string>> commands = {
        {"run", "run " + demo + " --participant P01 --db " + db + " --render none --quiet"},
        {"resume", "resume --db " + db + " --session 1 --render none --quiet"},
        {"export", "export --db " + db + " --out " + (dir / "export").string()},
        {"replay", "replay --db " + db + " --session 1 --trial 0 --out " + (dir / "replay").string()},
    };
    for (const auto& [name, args] : commands) {
      const auto r = run_cli(args);
      EXPECT_EQ(r.exit_code, 2) << name << " on " << f.label << ":\n" << r.out;
      EXPECT_EQ(r.out.rfind("curvlab: error: " + db + ": ", 0), 0u) << name << ":\n" << r.out;
      EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << name << ": expected one line:\n" << r.out;
      EXPECT_NE(r.out.find(f.says), std::string::npos) << name << ":\n" << r.out;
      const bool recoverable = f.kind == DataError::Kind::corrupt || f.label == "random bytes";
      EXPECT_EQ(r.out.find(" .recover | sqlite3 recovered.sqlite") != std::string::npos, recoverable)
          << name << ":\n" << r.out;
    }
    EXPECT_EQ(read_bytes(f.path), before) << f.label << " was modified";
    EXPECT_FALSE(fs::exists(dir / "export")) << "nothing is exported from a bad file";
    EXPECT_FALSE(fs::exists(dir / "replay"));
  }
}
