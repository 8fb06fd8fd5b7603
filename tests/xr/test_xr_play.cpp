// A play block in a headset through the real Khronos loader on the scripted
// test runtime: the right controller's grip (the cue's tip) swings through
// the cue ball, and the strike is read from its tracked motion — one shot by
// the participant along the swing.
#include "../cli/run_cli.hpp"
#include "runtime_env.hpp"
#include "../support/table_protocol.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sqlite3.h>
#include <unistd.h>

namespace {

using curvlab::testing::run_cli;
using curvlab::testing::RuntimeEnv;
namespace fs = std::filesystem;

TEST(XrPlay, AScriptedSwingOfTheRightControllerStrikesTheCueBall) {
  const auto dir = fs::temp_directory_path() / ("curvlab_xr_play_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "play.toml") << curvlab::test::table_protocol_head("play-xr", "a", "b") +
                                          "[[blocks]]\nname = \"play\"\nkind = \"play\"\nduration_s = 6\nshots = 1\n"
                                          "instructions = [\"Play.\"]\n";
  // The grip waits behind the cue ball (0.2 m in from the middle of edge 0,
  // at cue height), then moves 0.25 m toward the centre in 80 ms.
  std::string hand = "right@0.2=0,0.79,0.45";
  const double zs[] = {0.39, 0.33, 0.27, 0.23, 0.20};
  for (int i = 0; i < 5; ++i) {
    char item[64];
    std::snprintf(item, sizeof item, ";right@%.2f=0,0.79,%.2f", 2.5 + 0.02 * i, zs[i]);
    hand += item;
  }
  RuntimeEnv env({{"CURVLAB_TEST_XR_HAND", hand}, {"CURVLAB_TEST_XR_PRESS", "right:trigger@1.0"}});
  const auto db = (dir / "xr.db").string();
  const auto r = run_cli("run " + (dir / "play.toml").string() + " --participant X1 --db " + db +
                         " --backend xr --operator-window off --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  sqlite3* handle = nullptr;
  ASSERT_EQ(sqlite3_open_v2(db.c_str(), &handle, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(handle, "SELECT player, cue_speed_m_s, aim_z, event_count FROM shots", -1, &stmt,
                               nullptr),
            SQLITE_OK);
  ASSERT_EQ(sqlite3_step(stmt), SQLITE_ROW) << r.out;
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0))), "participant");
  EXPECT_GT(sqlite3_column_double(stmt, 1), 1.0);
  EXPECT_NEAR(sqlite3_column_double(stmt, 2), -1.0, 0.05);
  EXPECT_GT(sqlite3_column_int(stmt, 3), 0);
  sqlite3_finalize(stmt);
  sqlite3_close(handle);
  fs::remove_all(dir);
}

}  // namespace
