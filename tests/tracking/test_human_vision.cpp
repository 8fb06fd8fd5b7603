// The human observer (geometry/human_vision.hpp) against closed forms
// written here independently, in long double, for a horizontal stick
// straight ahead at eye height in E3:
//  - a point at (x, −Z) has yaws atan((x ± ipd/2) / Z) from the two eyes;
//    its vergence (disparity) is their difference;
//  - the fixated middle's vergence γ gives dioptres 2 tan(γ/2)/ipd, pulled
//    to w·that + (1 − w)/D_s; the perceived vergence is 2 atan(ipd·D'/2);
//  - every point's two yaws move by ± half the offset, and the lines meet
//    at Z = ipd / (tan a − tan b), x = Z tan a − ipd/2;
//  - the sagitta is the middle's distance from the ends' chord toward the
//    viewer (the chord is parallel to x here, so it is a difference of Z).
#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/geometry/maps.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace {

using namespace curvlab::geometry;
using LD = long double;

struct OracleStick {
  LD sagitta = 0.0L;          // perceived, metres
  LD perceived_distance = 0.0L;
};

// Oracle: the human observer's sagitta of a stick of length L whose ends lie
// at depth D and middle at D − h, eyes ipd apart, fixating the middle.
OracleStick oracle_stick(LD ipd, LD L, LD D, LD h, LD w, LD Ds) {
  const auto yaws = [&](LD x, LD Z) { return std::pair{std::atan((x + ipd / 2) / Z), std::atan((x - ipd / 2) / Z)}; };
  const auto [ml, mr] = yaws(0.0L, D - h);
  const LD gamma = ml - mr;
  const LD dioptres = w * 2 * std::tan(gamma / 2) / ipd + (1 - w) / Ds;
  const LD perceived = 2 * std::atan(ipd * dioptres / 2);
  const LD offset = perceived - gamma;
  const auto depth = [&](LD x, LD Z) {
    auto [a, b] = yaws(x, Z);
    a += offset / 2;
    b -= offset / 2;
    return ipd / (std::tan(a) - std::tan(b));
  };
  return {depth(-L / 2, D) - depth(0.0L, D - h), 1 / dioptres};
}

TEST(HumanVision, StickSagittaMatchesTheClosedFormInE3) {
  const Space e3{SpaceKind::E3, 1.0};
  const HumanVision v;
  const double ipd = 0.063;
  for (const double D : {0.4, 0.5, 0.8, 1.0, 1.5, 2.0, 3.0})
    for (const double h : {-0.02, 0.005, 0.03}) {
      const BentStick stick{1.0, h, 0.01};
      const auto seen = perceive_stick_human(e3, stick, D, eyes_from_ipd(ipd), ViewPreset::tourist, v);
      const OracleStick o = oracle_stick(ipd, 1.0L, D, h, v.vergence_weight, v.specific_distance_m);
      EXPECT_NEAR(seen.perceived_sagitta_m, static_cast<double>(o.sagitta), 1e-9 * std::abs(h)) << D << " " << h;
      EXPECT_NEAR(seen.percept.fixation.perceived_distance_m, static_cast<double>(o.perceived_distance), 1e-12);
      // The eyes reach every point of it: it fuses.
      EXPECT_TRUE(seen.percept.fused) << D << " " << h;
    }
}

// Johnston (1991): the same bend looks deeper near than far, and true where
// the perceived distance equals the real one (the specific distance). The
// gain is read against the same stick made straight, which itself looks
// curved away from the specific distance (the apparent frontal plane).
TEST(HumanVision, DepthIsStretchedNearAndFlattenedFarAndTrueAtTheSpecificDistance) {
  const Space e3{SpaceKind::E3, 1.0};
  const HumanVision v;
  const double h = 0.02;
  const auto sagitta = [&](double D, double bend) {
    return perceive_stick_human(e3, BentStick{1.0, bend, 0.01}, D, eyes_from_ipd(0.063), ViewPreset::tourist, v)
        .perceived_sagitta_m;
  };
  const auto ratio = [&](double D) { return sagitta(D, h) / h; };
  const auto gain = [&](double D) { return (sagitta(D, h) - sagitta(D, 0.0)) / h; };
  EXPECT_GT(ratio(0.5), ratio(2.0));
  EXPECT_GT(gain(0.5), 1.3);
  EXPECT_LT(gain(2.0), 0.7);
  // The middle fixated at exactly the specific distance: veridical.
  EXPECT_NEAR(ratio(v.specific_distance_m + h), 1.0, 1e-9);
  // Near it, within the shift of fixation that the bend itself makes.
  EXPECT_NEAR(gain(v.specific_distance_m), 1.0, 0.2);
  // The gain falls steadily with distance.
  double last = gain(0.5);
  for (double D = 0.55; D <= 4.0; D += 0.05) {
    const double g = gain(D);
    EXPECT_LT(g, last) << D;
    last = g;
  }
}

// The ideal geometer's sagitta blows up at the S3 quarter circumference
// (parallel sight lines); the human observer's stays finite and smooth. A
// geodesic stick centred there lies wholly at the quarter circumference (on
// the nose's polar sphere): every point has zero disparity, so the observer
// sees it at one vergence, bowed away along the Vieth–Müller circle through
// the perceived middle.
TEST(HumanVision, TheS3QuarterCircumferenceIsWellConditioned) {
  const double rho = 0.637;
  const Space s3{SpaceKind::S3, rho};
  const HumanVision v;
  const double quarter = rho * std::numbers::pi / 2.0;
  const BentStick straight{1.0, 0.0, 0.01};
  const auto eyes = eyes_from_ipd(0.063);
  const auto at = [&](double D) { return perceive_stick_human(s3, straight, D, eyes, ViewPreset::tourist, v); };
  const auto q = at(quarter);
  EXPECT_NEAR(q.percept.fixation.demand_rad, 0.0, 1e-14);
  EXPECT_NEAR(q.percept.fixation.perceived_distance_m, v.specific_distance_m / (1.0 - v.vergence_weight), 1e-12);
  EXPECT_TRUE(q.percept.fused);
  EXPECT_LT(q.perceived_sagitta_m, -0.5);
  double human_lo = 1e300, human_hi = -1e300, geometer_worst = 0.0;
  for (double d = -0.001; d <= 0.001; d += 0.0001) {
    const double s = at(quarter + d).perceived_sagitta_m;
    human_lo = std::min(human_lo, s);
    human_hi = std::max(human_hi, s);
    geometer_worst = std::max(
        geometer_worst, std::abs(perceive_stick(s3, straight, quarter + d, eyes, ViewPreset::tourist).perceived_sagitta_m));
  }
  EXPECT_LT(human_hi - human_lo, 0.01);
  EXPECT_GT(geometer_worst, 10.0);
}

TEST(HumanVision, TheEyesStopAtTheirDivergenceLimitAndTheStickIsThenSeenDouble) {
  const double rho = 0.637;
  const Space s3{SpaceKind::S3, rho};
  const HumanVision v;
  const BentStick straight{1.0, 0.0, 0.01};
  const auto eyes = eyes_from_ipd(0.063);
  // Far past the quarter circumference the eyes would have to diverge by
  // degrees: they stop at the limit, the residual is the pedestal, and it
  // exceeds the fusional limit.
  const auto far = perceive_stick_human(s3, straight, 0.9 * rho * std::numbers::pi, eyes, ViewPreset::tourist, v);
  const double limit = v.divergence_limit_deg * std::numbers::pi / 180.0;
  EXPECT_LT(far.percept.fixation.demand_rad, -limit);
  EXPECT_NEAR(far.percept.fixation.achieved_rad, -limit, 1e-15);
  EXPECT_LT(far.percept.fixation.pedestal_rad, 0.0);
  EXPECT_FALSE(far.percept.fused);
  EXPECT_GT(far.percept.threshold_rad, stereo_threshold_rad(v, 0.0));
  // Near, everything fuses at the base threshold.
  const auto near = perceive_stick_human(s3, straight, 0.6, eyes, ViewPreset::tourist, v);
  EXPECT_TRUE(near.percept.fused);
  EXPECT_DOUBLE_EQ(near.percept.threshold_rad, v.threshold_arcsec * std::numbers::pi / (180.0 * 3600.0));
}

TEST(HumanVision, ThresholdsAndFusionLimitsFollowTheirParameters) {
  HumanVision v;
  v.threshold_arcsec = 20.0;
  v.pedestal_fraction = 0.1;
  const double arcsec = std::numbers::pi / (180.0 * 3600.0);
  EXPECT_NEAR(stereo_threshold_rad(v, 0.0) / arcsec, 20.0, 1e-9);
  EXPECT_NEAR(stereo_threshold_rad(v, -600.0 * arcsec) / arcsec, 80.0, 1e-9);
  v.divergence_limit_deg = 1.0;
  v.convergence_limit_deg = 30.0;
  const double degree = std::numbers::pi / 180.0;
  EXPECT_EQ(beyond_reach_rad(v, 0.5 * degree), 0.0);
  EXPECT_EQ(beyond_reach_rad(v, -0.9 * degree), 0.0);
  EXPECT_NEAR(beyond_reach_rad(v, -1.5 * degree), -0.5 * degree, 1e-15);
  EXPECT_NEAR(beyond_reach_rad(v, 32.0 * degree), 2.0 * degree, 1e-15);
  // Depth per disparity at 1 m for 63 mm: ≈ D²/ipd.
  const Fixation f = fixate(HumanVision{.vergence_weight = 1.0}, 2.0 * std::atan(0.0315), 0.063);
  EXPECT_NEAR(f.perceived_distance_m, 1.0, 1e-12);
  EXPECT_NEAR(depth_per_disparity_m(f, 0.063), 1.0 / 0.063, 0.02);
}

TEST(HumanVision, MonocularViewingHasNoDisparityShape) {
  const Space e3{SpaceKind::E3, 1.0};
  const BentStick stick{1.0, 0.02, 0.01};
  EXPECT_EQ(perceive_stick_human(e3, stick, 1.0, eyes_from_ipd(0.063), ViewPreset::monocular, HumanVision{})
                .perceived_sagitta_m,
            0.0);
}

}  // namespace
