// The tracking commands as a user runs them: exit codes, JSON keys, and the
// numbers a methods developer checks.
#include "run_cli.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <sys/wait.h>

namespace {

using Result = curvlab::testing::CliResult;

Result run(const std::string& args) { return curvlab::testing::run_cli(args); }

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("curvlab_tracking_" + std::to_string(::getpid()) + "_" + name))
      .string();
}

nlohmann::json json_of(const Result& r) { return nlohmann::json::parse(r.out); }

TEST(TrackCli, WalkAroundThenTrackGivesTheSummaryKeys) {
  const std::string traj = temp_path("walk.csv");
  const std::string frames = temp_path("frames.csv");
  ASSERT_EQ(run("trajectory walk-around --laps 1.25 --out " + traj).exit_code, 0);
  const Result r = run("track --trajectory " + traj +
                       " --space H3 --algorithm table-anchored --json --out " + frames);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = json_of(r);
  for (const char* key : {"physical_edge", "virtual_edge", "virtual_laps", "max_coherence_error_m",
                          "max_coherence_error_rad"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["physical_edge"], 1);
  EXPECT_EQ(j["virtual_edge"], 0);
  EXPECT_NEAR(j["virtual_laps"].get<double>(), 1.0, 1e-9);
  EXPECT_LE(j["max_coherence_error_m"].get<double>(), 1e-9);
  std::ifstream f(frames);
  std::string header, first;
  std::getline(f, header);
  std::getline(f, first);
  EXPECT_EQ(header.rfind("t_ns,physical_edge,virtual_edge", 0), 0u);
  EXPECT_FALSE(first.empty());
  std::filesystem::remove(traj);
  std::filesystem::remove(frames);
}

TEST(TrackCli, ClockwiseWalkRunsTheLapsBackwards) {
  const std::string traj = temp_path("cw.csv");
  ASSERT_EQ(run("trajectory walk-around --laps 0.75 --direction cw --out " + traj).exit_code, 0);
  const Result r = run("track --trajectory " + traj + " --space S3 --algorithm table-anchored --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NEAR(json_of(r)["virtual_laps"].get<double>(), -1.0, 1e-9);
  std::filesystem::remove(traj);
}

TEST(TrackCli, EveryTrajectoryKindIsWritten) {
  for (const std::string kind : {"head-square --side-m 0.3", "hand-lap", "lean-over-center"}) {
    const std::string traj = temp_path("k.csv");
    const Result g = run("trajectory " + kind + " --out " + traj);
    ASSERT_EQ(g.exit_code, 0) << kind << ": " << g.out;
    const Result r = run("track --trajectory " + traj + " --space H3 --algorithm naive --json");
    EXPECT_EQ(r.exit_code, 0) << kind << ": " << r.out;
    std::filesystem::remove(traj);
  }
}

TEST(TrackCli, BadTrajectoryFileExitsTwoNamingLineAndField) {
  const std::string traj = temp_path("bad.csv");
  ASSERT_EQ(run("trajectory walk-around --laps 0.1 --out " + traj).exit_code, 0);
  {
    std::ofstream f(traj, std::ios::app);
    f << "99999999999,1,0,1.6,zz,1,0,0,0,1,0,0,0,1,0,0,0,1,0,0,0,1,0,0,0\n";
  }
  const Result r = run("track --trajectory " + traj + " --space H3 --algorithm naive");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find(traj + ":"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("field 'head_z_m'"), std::string::npos) << r.out;
  EXPECT_EQ(run("track --trajectory /nonexistent.csv --space H3 --algorithm naive").exit_code, 2);
  EXPECT_EQ(run("track --trajectory " + traj + " --space H3 --algorithm sideways").exit_code, 2);
  EXPECT_EQ(run("track --trajectory " + traj + " --space S3 --sides 5 --algorithm naive").exit_code, 2);
  EXPECT_EQ(run("track --trajectory " + traj + " --space H3 --radius-m 1 --edge-m 1 --algorithm naive").exit_code, 2);
  EXPECT_EQ(run("trajectory walk-around --laps -1 --out " + traj).exit_code, 2);
  EXPECT_EQ(run("trajectory head-square --out " + traj).exit_code, 2);  // --side-m required
  std::filesystem::remove(traj);
}

TEST(InspectCli, VergenceKeysAndTheS3QuarterCircle) {
  const Result r = run("inspect vergence --space S3 --radius-m 1 --ipd-m 0.063 --distance-m 2 --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = json_of(r);
  for (const char* key : {"vergence_deg", "tourist_distance_m", "native_distance_m"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_LT(j["vergence_deg"].get<double>(), 0.0);
  EXPECT_LT(j["tourist_distance_m"].get<double>(), 0.0);
  EXPECT_NEAR(j["native_distance_m"].get<double>(), 2.0, 1e-12);
  EXPECT_EQ(run("inspect vergence --space S3 --radius-m 1 --distance-m 4").exit_code, 2);  // > ρπ
  EXPECT_EQ(run("inspect vergence --space H3 --radius-m -1 --distance-m 1").exit_code, 2);
}

TEST(InspectCli, StickKeysAndBowDirection) {
  const Result h = run("inspect stick --space H3 --radius-m 0.85 --length-m 1 --distance-m 1 "
                       "--ipd-m 0.063 --view native --json");
  ASSERT_EQ(h.exit_code, 0) << h.out;
  const auto j = json_of(h);
  ASSERT_TRUE(j.contains("distances_m"));
  ASSERT_EQ(j["distances_m"].size(), 5u);
  EXPECT_NEAR(j["distances_m"][2].get<double>(), 1.0, 1e-12);
  EXPECT_GT(j["perceived_sagitta_m"].get<double>(), 0.0);
  const Result s = run("inspect stick --space S3 --radius-m 0.57 --length-m 1 --distance-m 1 "
                       "--ipd-m 0.063 --view native --json");
  EXPECT_LT(json_of(s)["perceived_sagitta_m"].get<double>(), 0.0);
  const Result t = run("inspect stick --space H3 --radius-m 0.85 --length-m 1 --distance-m 1 "
                       "--view tourist --bend-m 0 --json");
  EXPECT_NEAR(json_of(t)["perceived_sagitta_m"].get<double>(), 0.0, 1e-12);
  EXPECT_EQ(run("inspect stick --space H3 --radius-m 1 --length-m 1 --distance-m 1 --view sideways").exit_code, 2);
}

}  // namespace
