// Accuracy of the physical-table calibration against touch noise: for 3 and 4
// touched corners and several noise levels (standard deviation per coordinate),
// the RMS and worst errors of centre, edge, height and yaw over many simulated
// calibrations, and the share of calibrations within 2 mm (centre, edge,
// height) and 0.2° (yaw). The noise floor for the edge is σ/√Σ|q'|² (the
// least-squares scale's standard error), printed alongside.
#include "curvlab/geometry/calibration.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

int main() {
  using namespace curvlab::geometry;
  constexpr int kTrials = 20000;
  std::printf("%-7s %-8s %-10s %-10s %-10s %-10s %-10s %-10s %-10s %-9s %-9s\n", "corners",
              "sd_mm", "centre_rms", "centre_max", "edge_rms", "edge_sdth", "edge_max",
              "height_rms", "yaw_max°", "within%", "us/fit");
  for (int corners : {3, 4}) {
    for (double sd_mm : {0.25, 0.5, 1.0, 2.0, 5.0}) {
      std::mt19937_64 rng(1234);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      double c2 = 0, cmax = 0, e2 = 0, emax = 0, h2 = 0, ymax = 0;
      int within = 0, failed = 0;
      double elapsed_s = 0.0;
      for (int i = 0; i < kTrials; ++i) {
        PhysicalTableFit truth;
        truth.centre_m = {-2.0 + 4.0 * u(rng), -2.0 + 4.0 * u(rng)};
        truth.yaw_rad = -std::numbers::pi + 2.0 * std::numbers::pi * u(rng);
        truth.edge_m = 0.9;
        truth.height_m = 0.75;
        const auto touches = simulate_corner_touches(truth, corners, sd_mm * 1e-3, rng());
        const auto t0 = std::chrono::steady_clock::now();
        const auto result = fit_square_table(touches);
        elapsed_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (!std::holds_alternative<PhysicalTableFit>(result)) {
          ++failed;
          continue;
        }
        const auto& f = std::get<PhysicalTableFit>(result);
        const double dc = std::hypot(f.centre_m.x - truth.centre_m.x, f.centre_m.y - truth.centre_m.y);
        const double de = std::abs(f.edge_m - truth.edge_m);
        const double dh = std::abs(f.height_m - truth.height_m);
        const double dy = std::abs(std::remainder(f.yaw_rad - truth.yaw_rad, 2 * std::numbers::pi));
        c2 += dc * dc; e2 += de * de; h2 += dh * dh;
        cmax = std::max(cmax, dc); emax = std::max(emax, de); ymax = std::max(ymax, dy);
        if (dc < 2e-3 && de < 2e-3 && dh < 2e-3 && dy < 0.2 * std::numbers::pi / 180) ++within;
      }
      const int ok = kTrials - failed;
      const double q2 = corners == 4 ? 2.0 : 4.0 / 3.0;  // Σ|q'|² of the unit template
      std::printf("%-7d %-8.2f %-10.3f %-10.3f %-10.3f %-10.3f %-10.3f %-10.3f %-10.4f %-9.2f %-9.3f%s\n",
                  corners, sd_mm, 1e3 * std::sqrt(c2 / ok), 1e3 * cmax, 1e3 * std::sqrt(e2 / ok),
                  sd_mm / std::sqrt(q2), 1e3 * emax, 1e3 * std::sqrt(h2 / ok),
                  ymax * 180 / std::numbers::pi, 100.0 * within / kTrials,
                  1e6 * elapsed_s / kTrials,
                  failed ? (" rejected " + std::to_string(failed)).c_str() : "");
    }
  }
}
