// `curvlab calibrate --touches FILE.csv` as an experimenter runs it: noisy
// touches of a known table (simulate_corner_touches) give back its edge,
// centre and yaw, and the file `run --calibration` reads; bad sets and bad
// rows exit 2 with the reason.
#include "../cli/run_cli.hpp"

#include "curvlab/geometry/calibration.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <unistd.h>

namespace {

using curvlab::testing::run_cli;
using namespace curvlab::geometry;
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("curvlab_calibrate_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

PhysicalTableFit truth() {
  PhysicalTableFit t;
  t.centre_m = {0.32, -0.41};
  t.yaw_rad = 0.35;
  t.edge_m = 1.05;
  t.height_m = 0.74;
  return t;
}

std::string write_csv(const fs::path& path, const std::vector<Vec3>& touches, bool header = true) {
  std::ofstream out(path);
  if (header) out << "x_m,y_m,z_m\n";
  out.precision(17);
  for (const auto& p : touches) out << p.x << ',' << p.y << ',' << p.z << '\n';
  return path.string();
}

nlohmann::json json_of(const std::string& out) {
  const auto start = out.find('{');
  return start == std::string::npos ? nlohmann::json() : nlohmann::json::parse(out.substr(start), nullptr, false);
}

double angle_diff_rad(double a, double b) { return std::abs(std::remainder(a - b, 2.0 * std::numbers::pi)); }

TEST(CalibrateCli, RecoversEdgeCentreAndYawFromNoisyTouches) {
  const auto dir = fresh_dir("recover");
  const auto touches = simulate_corner_touches(truth(), 4, 0.001, 11);
  const auto csv = write_csv(dir / "touches.csv", touches);
  const auto out = dir / "table.json";
  const auto r = run_cli("calibrate --touches " + csv + " --edge-m 1.05 --json --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto doc = json_of(r.out);
  ASSERT_TRUE(doc.is_object()) << r.out;
  EXPECT_EQ(doc["edge_m"].get<double>(), 1.05);  // the known edge, kept
  EXPECT_NEAR(doc["fitted_edge_m"].get<double>(), 1.05, 0.003);  // and the touched one beside it
  EXPECT_NEAR(std::hypot(doc["centre_x_m"].get<double>() - 0.32, doc["centre_z_m"].get<double>() + 0.41), 0.0, 0.003);
  EXPECT_LT(angle_diff_rad(doc["yaw_rad"].get<double>(), 0.35), 0.3 * std::numbers::pi / 180.0);
  EXPECT_NEAR(doc["height_m"].get<double>(), 0.74, 0.003);
  EXPECT_EQ(doc["corners_used"], 4);
  // Each corner's residual, and the rms and max they give.
  ASSERT_EQ(doc["residuals_m"].size(), 4u);
  double sum2 = 0.0, largest = 0.0;
  for (const auto& v : doc["residuals_m"]) {
    const double r_m = v.get<double>();
    EXPECT_GT(r_m, 0.0);
    EXPECT_LT(r_m, 0.006);
    sum2 += r_m * r_m;
    largest = std::max(largest, r_m);
  }
  EXPECT_NEAR(doc["rms_residual_m"].get<double>(), std::sqrt(sum2 / 4.0), 1e-12);
  EXPECT_DOUBLE_EQ(doc["max_residual_m"].get<double>(), largest);
  ASSERT_EQ(doc["touches_m"].size(), 4u);
  EXPECT_DOUBLE_EQ(doc["touches_m"][2][0].get<double>(), touches[2].x);
  // --out holds the same calibration, and a session runs on it.
  std::ifstream file(out);
  EXPECT_EQ(nlohmann::json::parse(file), doc);
  const auto db = dir / "s.db";
  const auto run = run_cli(std::string("run ") + CURVLAB_SOURCE_DIR + "/protocols/demo.toml --participant C1 --db " +
                           db.string() + " --render none --quiet --calibration " + out.string());
  EXPECT_EQ(run.exit_code, 0) << run.out;
  fs::remove_all(dir);
}

TEST(CalibrateCli, ThreeTouchesWithoutAHeaderAreEnough) {
  const auto dir = fresh_dir("three");
  const auto csv = write_csv(dir / "touches.csv", simulate_corner_touches(truth(), 3, 0.0005, 3), false);
  const auto r = run_cli("calibrate --touches " + csv + " --edge-m 1.05");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("corners_used:"), std::string::npos) << r.out;  // human-readable without --json
  EXPECT_NE(r.out.find("edge_m:"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

TEST(CalibrateCli, BadSetsExitTwoWithTheReason) {
  const auto dir = fresh_dir("bad");
  const auto exact = simulate_corner_touches(truth(), 4, 0.0, 1);
  struct Case {
    std::string name;
    std::vector<Vec3> touches;
    std::string reason;
  };
  auto off = exact;
  off[2].x += 0.03;  // one touch 3 cm off
  PhysicalTableFit huge = truth();
  huge.edge_m = 10.0;
  PhysicalTableFit larger = truth();  // a table 30 mm larger than the one given
  larger.edge_m = 1.08;
  const std::vector<Case> cases = {
      {"clockwise", {exact[0], exact[3], exact[2], exact[1]}, "clockwise"},
      {"off", off, "touch 3 (back-right)"},
      {"huge", simulate_corner_touches(huge, 4, 0.0, 1), "outside 200.0 mm … 5000.0 mm"},
      {"larger", simulate_corner_touches(larger, 4, 0.0, 1),
       "the touches span a table of edge 1080.0 mm, the table as known has 1050.0 mm"},
      {"two", {exact[0], exact[1]}, "3 or 4 touched corners, got 2"},
  };
  for (const auto& c : cases) {
    const auto out = dir / (c.name + ".json");
    const auto r = run_cli("calibrate --touches " + write_csv(dir / (c.name + ".csv"), c.touches) +
                           " --edge-m 1.05 --out " + out.string());
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.out;
    EXPECT_NE(r.out.find(c.reason), std::string::npos) << c.name << ": " << r.out;
    EXPECT_NE(r.out.find(c.name + ".csv: "), std::string::npos) << c.name << ": " << r.out;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  fs::remove_all(dir);
}

TEST(CalibrateCli, ABadRowNamesFileLineAndField) {
  const auto dir = fresh_dir("rows");
  const auto csv = dir / "touches.csv";
  {
    std::ofstream out(csv);
    out << "x_m,y_m,z_m\n0.1,0.76,0.4\n\n0.5,0.76,abc\n";
  }
  auto r = run_cli("calibrate --touches " + csv.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(csv.string() + ":4: z_m: expected a number in metres, got 'abc'"), std::string::npos) << r.out;
  {
    std::ofstream out(csv);
    out << "0.1,0.76\n";
  }
  r = run_cli("calibrate --touches " + csv.string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(csv.string() + ":1: expected 3 values x_m,y_m,z_m"), std::string::npos) << r.out;
  r = run_cli("calibrate --touches " + (dir / "missing.csv").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("missing.csv: cannot read"), std::string::npos) << r.out;
  // Neither a file nor a backend, or a backend that has no hand to touch with.
  r = run_cli("calibrate");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--touches FILE.csv"), std::string::npos) << r.out;
  r = run_cli("calibrate --backend headless --out " + (dir / "t.json").string());
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--backend must be desktop or xr"), std::string::npos) << r.out;
  fs::remove_all(dir);
}

}  // namespace
