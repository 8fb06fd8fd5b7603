// `curvlab calibrate --backend xr` through the real Khronos loader on the
// scripted test runtime: the right controller's grip is put on each corner
// (CURVLAB_TEST_XR_HAND) and the trigger pulled; the first set has one
// touch 3 cm high and is refused, B starts again, the second set is fitted
// and kept with A. The tip offset is applied in the grip's frame.
#include "../cli/run_cli.hpp"
#include "runtime_env.hpp"

#include "curvlab/geometry/calibration.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <unistd.h>

namespace {

using curvlab::testing::run_cli;
using curvlab::testing::RuntimeEnv;
using namespace curvlab::geometry;
namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const auto dir = fs::temp_directory_path() / ("curvlab_xr_calibration_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// The scripted runtime's table: 1 m at the STAGE origin; the real one here
// is a little off, turned and lower.
PhysicalTableFit truth() {
  PhysicalTableFit t;
  t.centre_m = {-0.03, 0.05};
  t.yaw_rad = -0.08;
  t.edge_m = 0.98;
  t.height_m = 0.74;
  return t;
}

const Vec3 kTipOffset{0.0, -0.02, -0.06};  // in the grip frame; the scripted grips are unrotated

// "right@T=X,Y,Z" placements of the grip (tip − offset) and a trigger pull
// 0.3 s after each, one touch every 0.6 s from `start_s`.
void script_touches(const std::vector<Vec3>& touches, double start_s, std::string& hand, std::string& press) {
  char item[160];
  for (std::size_t j = 0; j < touches.size(); ++j) {
    const double at = start_s + 0.6 * static_cast<double>(j);
    const Vec3 grip = touches[j] - kTipOffset;
    std::snprintf(item, sizeof item, "%sright@%.2f=%.6f,%.6f,%.6f", hand.empty() ? "" : ";", at, grip.x, grip.y,
                  grip.z);
    hand += item;
    std::snprintf(item, sizeof item, "%sright:trigger@%.2f", press.empty() ? "" : ",", at + 0.3);
    press += item;
  }
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(XrCalibration, ControllerTouchesAreFittedAfterARefusedSetIsRedone) {
  const auto dir = fresh_dir("redo");
  auto first = simulate_corner_touches(truth(), 4, 0.0, 1);
  first[2].y += 0.03;  // the back-right corner touched 3 cm high
  const auto second = simulate_corner_touches(truth(), 4, 0.0, 1);
  std::string hand, press;
  script_touches(first, 0.5, hand, press);          // triggers 0.8 … 2.6 s: refused
  press += ",right:b@3.2";                          // touch the corners again
  script_touches(second, 3.6, hand, press);         // triggers 3.9 … 5.7 s: fitted
  press += ",right:a@6.4";                          // keep it
  const auto log_path = dir / "runtime.log";
  const auto out = dir / "table.json";
  RuntimeEnv env({{"CURVLAB_TEST_XR_HAND", hand},
                  {"CURVLAB_TEST_XR_PRESS", press},
                  {"CURVLAB_TEST_XR_LOG", log_path.string()}});
  const auto r = run_cli("calibrate --backend xr --edge-m 0.98 --tip-offset-m 0,-0.02,-0.06 --out " + out.string() +
                         " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("calibration: fit refused: the touches do not form a square table: touch 3 (back-right)"),
            std::string::npos)
      << r.out;
  // The second set, where the runtime put it (poses travel as floats).
  const auto doc = nlohmann::json::parse(read_text(out));
  const auto expected = std::get<PhysicalTableFit>(fit_square_table(second));
  EXPECT_NEAR(doc["centre_x_m"].get<double>(), expected.centre_m.x, 1e-5);
  EXPECT_NEAR(doc["centre_z_m"].get<double>(), expected.centre_m.y, 1e-5);
  EXPECT_NEAR(doc["yaw_rad"].get<double>(), -0.08, 1e-5);
  EXPECT_NEAR(doc["edge_m"].get<double>(), 0.98, 1e-5);
  EXPECT_NEAR(doc["height_m"].get<double>(), 0.74, 1e-5);
  EXPECT_LT(doc["max_residual_m"].get<double>(), 1e-5);
  ASSERT_EQ(doc["touches_m"].size(), 4u);
  for (std::size_t j = 0; j < 4; ++j)
    for (std::size_t i = 0; i < 3; ++i)
      EXPECT_NEAR(doc["touches_m"][j][i].get<double>(), second[j][static_cast<glm::length_t>(i)], 1e-5) << j;
  // The runtime saw no broken rule.
  std::istringstream log(read_text(log_path));
  std::string line;
  int ended_frames = 0;
  while (std::getline(log, line)) {
    EXPECT_NE(line.rfind("violation", 0), 0u) << line;
    EXPECT_NE(line.rfind("warning", 0), 0u) << line;
    ended_frames += line.rfind("end_frame", 0) == 0 ? 1 : 0;
  }
  EXPECT_GT(ended_frames, 400);  // 90 Hz for more than six seconds
  fs::remove_all(dir);
}

// Leaving before a fit is kept writes nothing and says why.
TEST(XrCalibration, ARuntimeExitBeforeAFitIsKeptWritesNothing) {
  const auto dir = fresh_dir("exit");
  const auto out = dir / "table.json";
  RuntimeEnv env(std::map<std::string, std::string>{{"CURVLAB_TEST_XR_EXIT", "0.5"}});
  const auto r = run_cli("calibrate --backend xr --out " + out.string());
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("the table calibration ended before a fit was accepted; nothing was written"),
            std::string::npos)
      << r.out;
  EXPECT_FALSE(fs::exists(out));
  fs::remove_all(dir);
}

}  // namespace
