// Physical-table calibration: the fitted table is compared with the table the
// touches were generated from. The ground-truth corners come from the E3
// square of table.hpp turned and moved with GLM, independently of the
// calibration's own corner formula.
#include "curvlab/geometry/calibration.hpp"
#include "curvlab/geometry/table.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

namespace {

using namespace curvlab::geometry;

struct Truth {
  double cx_m, cz_m, yaw_rad, edge_m, height_m;
};

// Corner j of the true table: table_corner() of an E3 square (centred, edge 0
// facing +z), turned about +y by the yaw and moved to the centre and height.
Vec3 true_corner(const Truth& t, int j) {
  const Space e3{SpaceKind::E3, 1.0};
  const auto shape = std::get<TableShape>(right_angled_table_from_edge(SpaceKind::E3, t.edge_m, 4));
  const Point p = table_corner(e3, shape, j);
  const glm::dmat4 turn = glm::rotate(glm::dmat4(1.0), t.yaw_rad, glm::dvec3(0.0, 1.0, 0.0));
  const glm::dvec4 q = turn * glm::dvec4(p.x, p.y, p.z, 1.0);
  return {q.x + t.cx_m, q.y + t.height_m, q.z + t.cz_m};
}

double angle_diff_rad(double a, double b) {
  return std::abs(std::remainder(a - b, 2.0 * std::numbers::pi));
}

std::vector<Vec3> noisy_touches(const Truth& t, int count, double sd_m, std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, sd_m);
  std::vector<Vec3> out;
  for (int j = 0; j < count; ++j) {
    const Vec3 c = true_corner(t, j);
    const double dx = noise(rng);
    const double dy = noise(rng);
    const double dz = noise(rng);
    out.push_back(c + Vec3(dx, dy, dz));
  }
  return out;
}

TEST(Calibration, ExactTouchesGiveTheTableExactly) {
  const Truth t{0.41, -1.3, 0.7, 0.9, 0.76};
  for (int count : {3, 4}) {
    std::vector<Vec3> touches;
    for (int j = 0; j < count; ++j) touches.push_back(true_corner(t, j));
    const auto result = fit_square_table(touches);
    ASSERT_TRUE(std::holds_alternative<PhysicalTableFit>(result))
        << std::get<GeometryError>(result).message;
    const auto& fit = std::get<PhysicalTableFit>(result);
    EXPECT_NEAR(fit.centre_m.x, t.cx_m, 1e-12);
    EXPECT_NEAR(fit.centre_m.y, t.cz_m, 1e-12);
    EXPECT_NEAR(angle_diff_rad(fit.yaw_rad, t.yaw_rad), 0.0, 1e-12);
    EXPECT_NEAR(fit.edge_m, t.edge_m, 1e-12);
    EXPECT_NEAR(fit.height_m, t.height_m, 1e-12);
    EXPECT_LT(fit.max_residual_m, 1e-12);
    EXPECT_EQ(fit.corners_used, count);
  }
}

struct Errors {
  double centre_rms_m = 0, edge_rms_m = 0, height_rms_m = 0;
  double centre_max_m = 0, edge_max_m = 0, height_max_m = 0, yaw_max_rad = 0;
  double share_within = 0;  // within 2 mm (centre, edge, height) and 0.2° (yaw)
};

// Fits 36 yaws × 40 seeds of random tables with touches of per-coordinate
// noise sd_m and collects the errors against the truth.
Errors sweep(int count, double sd_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Errors e;
  int n = 0, within = 0;
  for (int yaw_step = 0; yaw_step < 36; ++yaw_step) {
    for (int s = 0; s < 40; ++s) {
      const Truth t{-2.0 + 4.0 * uniform(rng), -2.0 + 4.0 * uniform(rng),
                    -std::numbers::pi + yaw_step * (2.0 * std::numbers::pi / 36.0) + 0.01,
                    0.8 + 0.4 * uniform(rng), 0.7 + 0.2 * uniform(rng)};
      const auto result = fit_square_table(noisy_touches(t, count, sd_m, rng));
      if (!std::holds_alternative<PhysicalTableFit>(result)) {
        ADD_FAILURE() << std::get<GeometryError>(result).message;
        continue;
      }
      const auto& fit = std::get<PhysicalTableFit>(result);
      const double dc = std::hypot(fit.centre_m.x - t.cx_m, fit.centre_m.y - t.cz_m);
      const double de = std::abs(fit.edge_m - t.edge_m);
      const double dh = std::abs(fit.height_m - t.height_m);
      const double dy = angle_diff_rad(fit.yaw_rad, t.yaw_rad);
      e.centre_rms_m += dc * dc;
      e.edge_rms_m += de * de;
      e.height_rms_m += dh * dh;
      e.centre_max_m = std::max(e.centre_max_m, dc);
      e.edge_max_m = std::max(e.edge_max_m, de);
      e.height_max_m = std::max(e.height_max_m, dh);
      e.yaw_max_rad = std::max(e.yaw_max_rad, dy);
      if (dc < 0.002 && de < 0.002 && dh < 0.002 && dy < 0.2 * std::numbers::pi / 180.0) ++within;
      ++n;
    }
  }
  e.centre_rms_m = std::sqrt(e.centre_rms_m / n);
  e.edge_rms_m = std::sqrt(e.edge_rms_m / n);
  e.height_rms_m = std::sqrt(e.height_rms_m / n);
  e.share_within = static_cast<double>(within) / n;
  return e;
}

// The acceptance figure at a noise where it can hold for every
// calibration: 0.5 mm per coordinate, every one of 1440 calibrations within
// 2 mm and 0.2°, with 3 and with 4 corners.
TEST(Calibration, HalfMillimetreNoiseAlwaysWithin2mmAnd0_2Degrees) {
  for (int count : {3, 4}) {
    const Errors e = sweep(count, 0.0005, 11 + static_cast<std::uint64_t>(count));
    EXPECT_LT(e.centre_max_m, 0.002) << count;
    EXPECT_LT(e.edge_max_m, 0.002) << count;
    EXPECT_LT(e.height_max_m, 0.002) << count;
    EXPECT_LT(e.yaw_max_rad, 0.2 * std::numbers::pi / 180.0) << count;
    EXPECT_EQ(e.share_within, 1.0) << count;
  }
}

// At 1 mm per coordinate the noise itself sets the floor: the least-squares
// edge has standard error σ/√Σ|q'|² (0.71 mm with 4 corners), so a few
// calibrations in a thousand land beyond 2 mm whatever the estimator. The fit
// must reach that floor (RMS errors equal to the closed-form standard errors
// within 10 %) and keep ≥ 99 % (4 corners) / ≥ 95 % (3 corners) within
// 2 mm and 0.2°.
TEST(Calibration, OneMillimetreNoiseReachesTheNoiseFloor) {
  const double sd_m = 0.001;
  for (int count : {3, 4}) {
    const Errors e = sweep(count, sd_m, 101 + static_cast<std::uint64_t>(count));
    // Σ|q'|² of the unit square's first `count` corners about their centroid.
    const double q2 = count == 4 ? 2.0 : 4.0 / 3.0;
    EXPECT_NEAR(e.edge_rms_m / (sd_m / std::sqrt(q2)), 1.0, 0.1) << count;
    EXPECT_NEAR(e.height_rms_m / (sd_m / std::sqrt(count)), 1.0, 0.1) << count;
    if (count == 4) {
      EXPECT_NEAR(e.centre_rms_m / (sd_m * std::sqrt(2.0 / 4.0)), 1.0, 0.1);
    }
    EXPECT_GE(e.share_within, count == 4 ? 0.99 : 0.95) << count;
    EXPECT_LT(e.yaw_max_rad, 0.3 * std::numbers::pi / 180.0) << count;
  }
}

TEST(Calibration, SimulatedCalibrationIsReproducibleAndRecovered) {
  PhysicalTableFit truth;
  truth.centre_m = {0.3, -0.8};
  truth.yaw_rad = -2.5;
  truth.edge_m = 1.1;
  truth.height_m = 0.74;
  const auto a = simulate_corner_touches(truth, 4, 0.001, 7);
  const auto b = simulate_corner_touches(truth, 4, 0.001, 7);
  const auto c = simulate_corner_touches(truth, 4, 0.001, 8);
  ASSERT_EQ(a.size(), 4u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  // The simulator's corners agree with the independent construction.
  const Truth t{0.3, -0.8, -2.5, 1.1, 0.74};
  const auto exact = simulate_corner_touches(truth, 4, 0.0, 1);
  for (int j = 0; j < 4; ++j) EXPECT_LT(glm::length(exact[static_cast<std::size_t>(j)] - true_corner(t, j)), 1e-12);
  const auto fit = std::get<PhysicalTableFit>(fit_square_table(a));
  EXPECT_LT(std::hypot(fit.centre_m.x - 0.3, fit.centre_m.y + 0.8), 0.002);
  EXPECT_LT(angle_diff_rad(fit.yaw_rad, -2.5), 0.2 * std::numbers::pi / 180.0);
}

// Each touch's residual is its distance from the fitted corner, in touch
// order; the largest is the one the fit names as worst.
TEST(Calibration, ResidualsAreGivenPerCorner) {
  const Truth t{0.2, -0.4, 0.5, 0.9, 0.75};
  std::vector<Vec3> touches;
  for (int j = 0; j < 4; ++j) touches.push_back(true_corner(t, j));
  touches[1].y += 0.006;  // 6 mm high: only the height moves, by a quarter of it
  const auto fit = std::get<PhysicalTableFit>(fit_square_table(touches));
  double sum2 = 0.0;
  for (int j = 0; j < 4; ++j) {
    const double r = glm::length(touches[static_cast<std::size_t>(j)] - physical_table_corner(fit, j));
    EXPECT_NEAR(fit.corner_residual_m[static_cast<std::size_t>(j)], r, 1e-12) << j;
    sum2 += r * r;
  }
  EXPECT_NEAR(fit.corner_residual_m[1], 0.0045, 1e-9);
  EXPECT_NEAR(fit.corner_residual_m[0], 0.0015, 1e-9);
  EXPECT_EQ(fit.worst_corner, 1);
  EXPECT_DOUBLE_EQ(fit.max_residual_m, fit.corner_residual_m[1]);
  EXPECT_NEAR(fit.rms_residual_m, std::sqrt(sum2 / 4.0), 1e-12);
  // Three corners: the fourth entry stays 0.
  touches.pop_back();
  const auto three = std::get<PhysicalTableFit>(fit_square_table(touches));
  EXPECT_EQ(three.corner_residual_m[3], 0.0);
  EXPECT_GT(three.corner_residual_m[1], 0.0);
}

std::string error_of(const std::vector<Vec3>& touches) {
  const auto result = fit_square_table(touches);
  if (std::holds_alternative<PhysicalTableFit>(result)) return "";
  return std::get<GeometryError>(result).message;
}

TEST(Calibration, ClockwiseOrderIsRejectedWithTheRightOrder) {
  const Truth t{0.0, 0.0, 0.3, 0.9, 0.75};
  std::vector<Vec3> touches = {true_corner(t, 0), true_corner(t, 3), true_corner(t, 2),
                               true_corner(t, 1)};
  const std::string msg = error_of(touches);
  EXPECT_NE(msg.find("clockwise"), std::string::npos) << msg;
  EXPECT_NE(msg.find("front-left, front-right, back-right, back-left"), std::string::npos) << msg;
  touches.pop_back();
  EXPECT_NE(error_of(touches).find("clockwise"), std::string::npos);
}

TEST(Calibration, CrossedOrderIsNotASquare) {
  const Truth t{0.0, 0.0, 0.3, 0.9, 0.75};
  const std::vector<Vec3> touches = {true_corner(t, 0), true_corner(t, 2), true_corner(t, 1),
                                     true_corner(t, 3)};
  const std::string msg = error_of(touches);
  EXPECT_NE(msg.find("do not form a square"), std::string::npos) << msg;
}

TEST(Calibration, ABadTouchIsNamed) {
  const Truth t{0.2, 0.1, 1.0, 0.9, 0.75};
  std::vector<Vec3> touches;
  for (int j = 0; j < 4; ++j) touches.push_back(true_corner(t, j));
  touches[2].y += 0.08;  // touched the floor-side of the cushion, 8 cm too high
  const std::string msg = error_of(touches);
  EXPECT_NE(msg.find("touch 3 (back-right)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("limit 15.0 mm"), std::string::npos) << msg;

  // A rectangle, not a square: 0.9 × 1.5 m.
  std::vector<Vec3> rect = {{-0.45, 0.75, 0.75}, {0.45, 0.75, 0.75}, {0.45, 0.75, -0.75},
                            {-0.45, 0.75, -0.75}};
  EXPECT_NE(error_of(rect).find("do not form a square"), std::string::npos);
}

TEST(Calibration, DegenerateInputIsRejected) {
  EXPECT_NE(error_of({{0, 0, 0}, {1, 0, 0}}).find("3 or 4"), std::string::npos);
  EXPECT_NE(error_of({{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}).find("outside"), std::string::npos);
  EXPECT_NE(error_of({{0, 0, 0}, {NAN, 0, 0}, {0, 0, 1}}).find("non-finite"), std::string::npos);
}

// Against the known table (its edge given): one corner touched 30 mm off,
// in any direction and at any corner, is refused — a free fit would let the
// edge absorb part of it and leave the touch near the 15 mm limit, accepted
// or refused by chance.
TEST(Calibration, OneCorner30mmOffInAnyDirectionIsRefusedAgainstTheKnownEdge) {
  const Truth t{0.2, -0.1, 0.4, 1.0, 0.76};
  CalibrationLimits known;
  known.known_edge_m = 1.0;
  int free_accepted = 0;
  for (int corner = 0; corner < 4; ++corner) {
    for (int k = 0; k < 16; ++k) {
      // 14 directions in the floor plane and straight up and down.
      Vec3 off{0.0};
      if (k < 14) {
        const double a = 2.0 * std::numbers::pi * k / 14.0;
        off = {0.030 * std::cos(a), 0.0, 0.030 * std::sin(a)};
      } else {
        off = {0.0, k == 14 ? 0.030 : -0.030, 0.0};
      }
      std::vector<Vec3> touches;
      for (int j = 0; j < 4; ++j) touches.push_back(true_corner(t, j));
      touches[static_cast<std::size_t>(corner)] += off;
      const auto fitted = fit_square_table(touches, known);
      EXPECT_TRUE(std::holds_alternative<GeometryError>(fitted))
          << "corner " << corner << " moved by (" << off.x << ", " << off.y << ", " << off.z << ") m was accepted";
      if (std::holds_alternative<PhysicalTableFit>(fit_square_table(touches))) ++free_accepted;
    }
  }
  // The free fit, by contrast, accepts some of these.
  EXPECT_GT(free_accepted, 0);
}

// Exact touches of the known table: the fit keeps its edge and reports the
// one the touches span beside it; a physical table 25 mm larger is refused
// naming both edges and the tolerance.
TEST(Calibration, TheKnownEdgeIsKeptAndADifferentTableIsRefused) {
  CalibrationLimits known;
  known.known_edge_m = 1.0;
  std::mt19937_64 rng(7);
  const auto good = fit_square_table(noisy_touches(Truth{0.1, 0.2, -0.3, 1.0, 0.76}, 4, 0.001, rng), known);
  ASSERT_TRUE(std::holds_alternative<PhysicalTableFit>(good));
  const auto& fit = std::get<PhysicalTableFit>(good);
  EXPECT_EQ(fit.edge_m, 1.0);
  EXPECT_NEAR(fit.fitted_edge_m, 1.0, 0.003);

  std::vector<Vec3> larger;
  for (int j = 0; j < 4; ++j) larger.push_back(true_corner(Truth{0.0, 0.0, 0.0, 1.025, 0.76}, j));
  const auto refused = fit_square_table(larger, known);
  ASSERT_TRUE(std::holds_alternative<GeometryError>(refused));
  const std::string msg = std::get<GeometryError>(refused).message;
  EXPECT_NE(msg.find("the touches span a table of edge 1025.0 mm, the table as known has 1000.0 mm"),
            std::string::npos)
      << msg;
  EXPECT_NE(msg.find("more than the 10.0 mm tolerance"), std::string::npos) << msg;
  // Without a known edge the same touches fit a 1.025 m table.
  EXPECT_TRUE(std::holds_alternative<PhysicalTableFit>(fit_square_table(larger)));
}

}  // namespace
