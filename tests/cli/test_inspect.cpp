#include "run_cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>

namespace curvlab::testing {
namespace {

using nlohmann::json;

json run_json(const std::string& args) {
  const CliResult r = run_cli(args + " --json");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  return json::parse(r.out);
}

TEST(InspectTable, H3PentagonForA90cmEdge) {
  const json j = run_json("inspect table --space H3 --edge-m 0.9");
  EXPECT_EQ(j["sides"], 5);
  EXPECT_NEAR(j["side_rad"].get<double>(), std::acosh((1.0 + std::sqrt(5.0)) / 2.0), 1e-14);
  EXPECT_NEAR(j["radius_m"].get<double>() * j["side_rad"].get<double>(), 0.9, 1e-14);
  EXPECT_NEAR(j["interior_angle_deg"].get<double>(), 90.0, 1e-12);
  EXPECT_NEAR(j["physical_laps_per_virtual_lap"].get<double>(), 1.25, 0.0);
  EXPECT_TRUE(j.contains("circumradius_m"));
}

TEST(InspectTable, E3RadiusDefaultsToOneMetre) {
  const json j = run_json("inspect table --space E3 --edge-m 0.9");
  EXPECT_EQ(j["sides"], 4);
  EXPECT_NEAR(j["radius_m"].get<double>(), 1.0, 0.0);
  EXPECT_NEAR(j["side_rad"].get<double>(), 0.9, 1e-15);
  const json k = run_json("inspect table --space E3 --edge-m 0.9 --radius-m 3");
  EXPECT_NEAR(k["side_rad"].get<double>(), 0.3, 1e-15);
}

TEST(InspectTable, ImpossibleSidesAreRefusedWithExitCode2) {
  const CliResult r = run_cli("inspect table --space S3 --edge-m 0.9 --sides 4");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("90°"), std::string::npos) << r.out;
  EXPECT_EQ(run_cli("inspect table --space Q3 --edge-m 0.9").exit_code, 2);
  EXPECT_EQ(run_cli("inspect table --space H3 --edge-m -1").exit_code, 2);
  EXPECT_EQ(run_cli("inspect table --space H3 --edge-m abc").exit_code, 2);
}

TEST(InspectHolonomy, SignFollowsCurvature) {
  const json s3 = run_json("inspect holonomy --space S3 --theta-rad 0.05");
  const json h3 = run_json("inspect holonomy --space H3 --theta-rad 0.05");
  EXPECT_NEAR(s3["rotation_rad"].get<double>(), 0.0025, 0.0025 * 0.01);
  EXPECT_NEAR(h3["rotation_rad"].get<double>(), -0.0025, 0.0025 * 0.01);
  EXPECT_NEAR(s3["offset_rad"].get<double>(), std::pow(0.05, 3) / std::sqrt(2.0), 1e-6);
  EXPECT_EQ(run_cli("inspect holonomy --space S3 --theta-rad 4").exit_code, 2);
}

TEST(InspectMap, S3PointGivesFrontAndBackImages) {
  // θ = 2.5 rad straight ahead (−z) on the unit 3-sphere.
  const double t = 2.5;
  char pt[128];
  std::snprintf(pt, sizeof pt, "0,0,%.17g,%.17g", -std::sin(t), std::cos(t));
  const json j = run_json(std::string("inspect map --space S3 --radius-m 1 --point ") + pt);
  EXPECT_NEAR(j["theta_rad"].get<double>(), t, 1e-6);
  EXPECT_NEAR(j["native_m"][2].get<double>(), -t, 1e-6);
  EXPECT_NEAR(j["back_native_m"][2].get<double>(), 2.0 * M_PI - t, 1e-6);
}

TEST(InspectMap, PointOffTheSpaceIsRejectedWithAClearMessage) {
  const CliResult r = run_cli("inspect map --space H3 --radius-m 1 --point 1,0,0,1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("not on H3"), std::string::npos) << r.out;
  EXPECT_EQ(run_cli("inspect map --space S3 --radius-m 1 --point 1,2,3").exit_code, 2);
  EXPECT_EQ(run_cli("inspect map --space E3 --radius-m 0 --point 0,0,0,0").exit_code, 2);
}

TEST(Help, EveryCommandHasHelp) {
  for (const char* cmd : {"--help", "inspect --help", "inspect table --help", "inspect holonomy --help",
                          "inspect map --help"}) {
    const CliResult r = run_cli(cmd);
    EXPECT_EQ(r.exit_code, 0) << cmd;
    EXPECT_NE(r.out.find("Usage"), std::string::npos) << cmd;
  }
}

}  // namespace
}  // namespace curvlab::testing
