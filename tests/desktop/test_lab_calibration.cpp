// The table calibration in the desktop window on Xvfb, as a pilot scripts it:
// the right hand put on each corner by the key script and space pressed,
// a refused set touched again, the fit kept with Enter; then a protocol with
// [calibration] at_start runs its session on the table it calibrated.
#include "../cli/run_cli.hpp"
#include "../runner/session_db.hpp"
#include "../support/png_files.hpp"
#include "xvfb.hpp"

#include "curvlab/geometry/calibration.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

using curvlab::testing::fresh_dir;
using curvlab::testing::run_cli;
using namespace curvlab::geometry;
namespace fs = std::filesystem;

// The real table: off the lab origin, turned, smaller than the protocol's.
PhysicalTableFit truth() {
  PhysicalTableFit t;
  t.centre_m = {0.06, -0.04};
  t.yaw_rad = 0.12;
  t.edge_m = 0.94;
  t.height_m = 0.77;
  return t;
}

// Key-script lines that put the right hand on each touch and press space.
std::string touch_lines(const std::vector<Vec3>& touches) {
  std::ostringstream out;
  out.precision(17);
  for (const auto& p : touches) out << "hand right " << p.x << ' ' << p.y << ' ' << p.z << " 60\nspace 60\n";
  return out.str();
}

// The limits of a fit that knows the table's edge, as calibrate and run give it.
CalibrationLimits known_edge(double edge_m) {
  CalibrationLimits l;
  l.known_edge_m = edge_m;
  return l;
}

void expect_same_table(const nlohmann::json& doc, const PhysicalTableFit& fit, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_NEAR(doc["centre_x_m"].get<double>(), fit.centre_m.x, 1e-9);
  EXPECT_NEAR(doc["centre_z_m"].get<double>(), fit.centre_m.y, 1e-9);
  EXPECT_NEAR(doc["yaw_rad"].get<double>(), fit.yaw_rad, 1e-9);
  EXPECT_NEAR(doc["edge_m"].get<double>(), fit.edge_m, 1e-9);
  EXPECT_NEAR(doc["height_m"].get<double>(), fit.height_m, 1e-9);
  EXPECT_NEAR(doc["max_residual_m"].get<double>(), fit.max_residual_m, 1e-9);
  EXPECT_EQ(doc["corners_used"], fit.corners_used);
  ASSERT_EQ(doc["residuals_m"].size(), static_cast<std::size_t>(fit.corners_used));
  for (int j = 0; j < fit.corners_used; ++j)
    EXPECT_NEAR(doc["residuals_m"][static_cast<std::size_t>(j)].get<double>(),
                fit.corner_residual_m[static_cast<std::size_t>(j)], 1e-9);
}

// Pixels of a colour in an image.
template <class Pred>
int count(const curvlab::renderer::Rgba8Image& img, Pred pred) {
  int n = 0;
  for (std::size_t i = 0; i + 3 < img.pixels.size(); i += 4)
    if (pred(img.pixels[i], img.pixels[i + 1], img.pixels[i + 2])) ++n;
  return n;
}

bool yellow(int r, int g, int b) { return r > 170 && g > 140 && b < 90; }
bool red(int r, int g, int b) { return r > 150 && r > g + 90 && r > b + 90; }

TEST(LabCalibration, DesktopTouchesAreFittedAfterARefusedSetIsRedone) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  const auto dir = fresh_dir("desktop");
  // Three corners, one touched 8 cm high, fitted on F: refused; R; then all four.
  auto bad = simulate_corner_touches(truth(), 3, 0.0, 1);
  bad[1].y += 0.08;
  const auto good = simulate_corner_touches(truth(), 4, 0.001, 5);
  {
    std::ofstream keys(dir / "keys.txt");
    keys << touch_lines(bad) << "f 60\nr 60\n" << touch_lines(good) << "enter 60\n";
  }
  const auto out = dir / "table.json";
  const auto shots = dir / "shots";
  const auto r = run_cli("calibrate --backend desktop --edge-m 0.94 --software --window-size 320x320 --key-script " +
                         (dir / "keys.txt").string() + " --out " + out.string() + " --screenshot " +
                         shots.string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("calibration: fit refused: the touches do not form a square table: touch 2 (front-right)"),
            std::string::npos)
      << r.out;
  const auto expected = std::get<PhysicalTableFit>(fit_square_table(good, known_edge(0.94)));
  std::ifstream file(out);
  const auto doc = nlohmann::json::parse(file);
  expect_same_table(doc, expected, "--out");
  EXPECT_NEAR(doc["edge_m"].get<double>(), 0.94, 0.004);
  ASSERT_EQ(doc["touches_m"].size(), 4u);
  EXPECT_NEAR(doc["touches_m"][3][2].get<double>(), good[3].z, 1e-9);

  // What the participant saw: the yellow marker on the first corner to
  // touch, and the refused touches in red.
  curvlab::renderer::Rgba8Image first, refused;
  ASSERT_TRUE(curvlab::test::read_png_into((shots / "calibration_01_touch_front-left_left.png").string(), first));
  EXPECT_GT(count(first, yellow), 5) << "no corner marker";
  ASSERT_TRUE(curvlab::test::read_png_into((shots / "calibration_05_refused_left.png").string(), refused));
  EXPECT_GT(count(refused, red), 5) << "the refused touches are not shown";
  EXPECT_TRUE(fs::exists(shots / "calibration_10_fitted_window.png"));
  EXPECT_TRUE(fs::exists(shots / "calibration_11_accepted_window.png"));
  fs::remove_all(dir);
}

TEST(LabCalibration, AProtocolThatCalibratesAtStartRunsOnTheFittedTable) {
  curvlab::test::XServer x;
  if (!x.available()) GTEST_SKIP() << "no X display: " << x.reason();
  const auto dir = fresh_dir("run");
  std::ifstream demo(std::string(CURVLAB_SOURCE_DIR) + "/protocols/demo.toml");
  std::ostringstream text;
  text << demo.rdbuf() << "\n[calibration]\nat_start = true\ntip_offset_m = [0.0, -0.02, -0.05]\n";
  // The lab's table, which the virtual one's edges equal.
  std::string protocol_text = text.str();
  const auto edge = protocol_text.find("edge_m = 1.0\n");
  ASSERT_NE(edge, std::string::npos);
  protocol_text.replace(edge, 13, "edge_m = 0.94\n");
  const auto protocol = dir / "calibrated.toml";
  std::ofstream(protocol) << protocol_text;
  // The pilot body starts facing −z (toward the table centre), so its
  // hand's grip frame is the lab's: the tip is the grip plus the offset.
  const auto touches = simulate_corner_touches(truth(), 4, 0.001, 9);
  std::vector<Vec3> grips;
  for (const auto& t : touches) grips.push_back(t - Vec3(0.0, -0.02, -0.05));
  {
    std::ofstream keys(dir / "keys.txt");
    keys << touch_lines(grips) << "enter 60\nspace 100\n";
    for (int i = 0; i < 8; ++i) keys << "2 100\n";
    keys << "space 100\nspace 100\n";
  }
  const auto db = dir / "s.db";
  const auto r = run_cli("run " + protocol.string() + " --participant K1 --db " + db.string() +
                         " --backend desktop --software --window-size 256x256 --key-script " +
                         (dir / "keys.txt").string() + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("\"status\": \"completed\""), std::string::npos) << r.out;
  const auto rows = curvlab::testing::query(db.string(), "SELECT table_calibration FROM sessions");
  ASSERT_EQ(rows.size(), 1u);
  const auto stored = nlohmann::json::parse(rows[0][0]);
  expect_same_table(stored, std::get<PhysicalTableFit>(fit_square_table(touches, known_edge(0.94))),
                    "sessions.table_calibration");
  fs::remove_all(dir);
}

}  // namespace
