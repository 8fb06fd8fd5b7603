// The platform layer (harness/include/curvlab/harness/platform/) behaves the
// same on Linux and on Windows: these tests run in the Linux build (label
// unit) and, built by scripts/build_windows.sh, under Wine (label windows).
// What they guard is what a lab would notice: a second writer of a session
// is refused and told who holds it, a dead writer's session is free at once,
// an export replaces its target, Ctrl-C stops a session.
#include "curvlab/harness/data/writer_lock.hpp"
#include "curvlab/harness/platform/files.hpp"
#include "curvlab/harness/platform/lock_file.hpp"
#include "curvlab/harness/platform/process.hpp"
#include "curvlab/harness/platform/signals.hpp"

#include <gtest/gtest.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
namespace pf = curvlab::harness::platform;
using curvlab::harness::data::WriterLock;

namespace {

// A fresh folder under the system's temporary folder, removed afterwards.
class PlatformTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("curvlab-platform-" + std::to_string(pf::process_id()) + "-" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  [[nodiscard]] std::string path(const std::string& name) const { return (dir_ / name).string(); }

  static std::string read(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  static void write(const std::string& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

  fs::path dir_;
};

TEST_F(PlatformTest, AByteLockedThroughOneOpenIsRefusedThroughAnotherUntilThatOneCloses) {
  const std::string p = path("x.lock");
  pf::LockFile a = pf::LockFile::open(p, pf::LockFile::Mode::create_read_write);
  pf::LockFile b = pf::LockFile::open(p, pf::LockFile::Mode::create_read_write);
  ASSERT_TRUE(a.is_open());
  ASSERT_TRUE(b.is_open());
  ASSERT_TRUE(a.try_lock(3, true));
  EXPECT_FALSE(b.try_lock(3, true));
  EXPECT_FALSE(b.try_lock(3, false));
  EXPECT_TRUE(b.held_elsewhere(3, true));
  EXPECT_FALSE(a.held_elsewhere(3, true)) << "a lock never conflicts with its own open";
  EXPECT_TRUE(b.try_lock(4, true)) << "other bytes are free";
  a.close();  // as the system does when the holder dies
  EXPECT_FALSE(b.held_elsewhere(3, true));
  EXPECT_TRUE(b.try_lock(3, true));
}

TEST_F(PlatformTest, SharedLocksCoexistAndKeepAnExclusiveOneOut) {
  const std::string p = path("x.lock");
  auto a = pf::LockFile::open(p, pf::LockFile::Mode::create_read_write);
  auto b = pf::LockFile::open(p, pf::LockFile::Mode::create_read_write);
  auto c = pf::LockFile::open(p, pf::LockFile::Mode::read_only);
  ASSERT_TRUE(c.is_open());
  ASSERT_TRUE(a.try_lock(0, false));
  EXPECT_TRUE(b.try_lock(0, false));
  EXPECT_TRUE(c.held_elsewhere(0, true));
  EXPECT_FALSE(c.held_elsewhere(0, false));
  EXPECT_FALSE(c.try_lock(0, true));
}

TEST_F(PlatformTest, SlotsWrittenThroughOneOpenAreReadThroughAnother) {
  const std::string p = path("x.lock");
  auto a = pf::LockFile::open(p, pf::LockFile::Mode::create_read_write);
  ASSERT_TRUE(a.try_lock(1, true));
  a.write_at("1234 host", 65536 + 128);
  auto b = pf::LockFile::open(p, pf::LockFile::Mode::read_only);
  EXPECT_EQ(b.read_at(9, 65536 + 128), "1234 host");
  EXPECT_EQ(b.size(), 65536 + 128 + 9);
  EXPECT_TRUE(b.read_at(4, 1 << 20).empty()) << "past the end";
}

TEST_F(PlatformTest, OpeningAMissingLockFileReadOnlyFailsWithoutMakingIt) {
  auto f = pf::LockFile::open(path("none.lock"), pf::LockFile::Mode::read_only);
  EXPECT_FALSE(f.is_open());
  EXPECT_EQ(f.error(), ENOENT);
  EXPECT_FALSE(fs::exists(path("none.lock")));
}

TEST_F(PlatformTest, ASecondWriterOfASessionIsRefusedAndToldWhichProcessHoldsIt) {
  const std::string db = path("study.sqlite");
  auto first = WriterLock::for_session(db, 2);
  ASSERT_TRUE(first) << first.error().message;
  auto second = WriterLock::for_session(db, 2);
  ASSERT_FALSE(second);
  EXPECT_EQ(second.error().kind, curvlab::harness::data::DataError::Kind::in_use);
  EXPECT_NE(second.error().message.find("process " + std::to_string(pf::process_id())), std::string::npos)
      << second.error().message;
  EXPECT_TRUE(WriterLock::for_session(db, 3)) << "another session of the same file is free";
  auto replacing = WriterLock::for_replacing(db);
  ASSERT_FALSE(replacing);
  EXPECT_NE(replacing.error().message.find("session 2"), std::string::npos) << replacing.error().message;
  ASSERT_TRUE(WriterLock::session_writer(db, 2).has_value());
  EXPECT_EQ(WriterLock::session_writer(db, 2)->pid, pf::process_id());
  EXPECT_TRUE(fs::exists(db + ".reserve-2")) << "disk set aside for the session's end";

  { auto released = std::move(*first); }
  EXPECT_FALSE(WriterLock::session_writer(db, 2).has_value());
  EXPECT_FALSE(fs::exists(db + ".reserve-2"));
  EXPECT_TRUE(WriterLock::for_session(db, 2));
}

TEST_F(PlatformTest, RenameReplacesAFileOrAnEmptyFolderButNotAFolderWithContent) {
  write(path("new"), "new");
  write(path("old"), "old");
  ASSERT_EQ(pf::rename_replacing(path("new"), path("old")), 0);
  EXPECT_EQ(read(path("old")), "new");
  EXPECT_FALSE(fs::exists(path("new")));

  fs::create_directories(path("staged"));
  write(path("staged/a.csv"), "a");
  fs::create_directories(path("empty"));
  ASSERT_EQ(pf::rename_replacing(path("staged"), path("empty")), 0);
  EXPECT_EQ(read(path("empty/a.csv")), "a");

  fs::create_directories(path("staged2"));
  const int err = pf::rename_replacing(path("staged2"), path("empty"));
  EXPECT_TRUE(err == ENOTEMPTY || err == EEXIST) << err;
  EXPECT_EQ(read(path("empty/a.csv")), "a") << "left as it was";
}

TEST_F(PlatformTest, ANewFileIsCreatedOnlyOnce) {
  std::FILE* f = pf::create_new_file(path("p.toml"));
  ASSERT_NE(f, nullptr);
  std::fputs("a\n", f);
  std::fclose(f);
  EXPECT_EQ(pf::create_new_file(path("p.toml")), nullptr);
  EXPECT_EQ(read(path("p.toml")), "a\n") << "written in binary: the same bytes on every platform";
}

TEST_F(PlatformTest, ProcessesFoldersAndDisksAreSeenAsTheyAre) {
  EXPECT_TRUE(pf::process_alive(pf::process_id()));
  EXPECT_FALSE(pf::process_alive(0));
  EXPECT_FALSE(pf::process_alive(2147483647));
  EXPECT_TRUE(pf::writable(dir_.string()));
  EXPECT_FALSE(pf::writable(path("missing/folder")));
  const auto free = pf::free_bytes(dir_.string());
  ASSERT_TRUE(free.has_value());
  EXPECT_GT(*free, 0u);
  EXPECT_FALSE(pf::host_name().empty());
  EXPECT_EQ(pf::utc_now_iso8601().size(), 20u);
}

TEST(PlatformSignals, CtrlCIsCaughtOnceAndNamed) {
  const std::atomic<int>& caught = pf::catch_stop_signals();
  EXPECT_EQ(pf::stop_signal_received(), 0);
  std::raise(SIGINT);
  EXPECT_EQ(caught.load(), SIGINT);
  EXPECT_EQ(pf::stop_signal_received(), SIGINT);
  EXPECT_EQ(pf::signal_name(SIGINT), "Interrupt");
  EXPECT_EQ(pf::signal_name(SIGTERM), "Terminated");
}

}  // namespace
