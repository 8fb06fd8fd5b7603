#include "helpers.hpp"

#include "curvlab/geometry/maps.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace curvlab::testing {
namespace {

using namespace geometry;
constexpr double kPi = std::numbers::pi;

// A point at distance theta (radians) from the origin in direction u, built
// in quad precision and rounded once to double.
Point point_at(SpaceKind kind, const Vec3& u, double theta, double rho) {
  const auto t = oracle::translation(to_oracle(kind), u.x, u.y, u.z, theta);
  oracle::QVec4 o;
  o[3] = rho;
  return to_d(oracle::mul(t, o));
}

double rel_err_log(const Space& s, const Point& p) {
  const Vec3 got = log_origin(s, p);
  const auto want = oracle::log_origin(to_oracle(s.kind), to_q(p), s.radius_m);
  const double n = oracle::to_d(sqrtq(want[0] * want[0] + want[1] * want[1] + want[2] * want[2]));
  const double dx = got.x - oracle::to_d(want[0]);
  const double dy = got.y - oracle::to_d(want[1]);
  const double dz = got.z - oracle::to_d(want[2]);
  return std::sqrt(dx * dx + dy * dy + dz * dz) / n;
}

TEST(LogMap, MatchesOracleOverTheWholeRangeInS3) {
  Rng rng(10);
  const Space s{SpaceKind::S3, 1.7};
  for (double theta = 1e-8; theta < kPi - 1e-6; theta *= 1.3) {
    const Point p = point_at(s.kind, rng.unit(), theta, s.radius_m);
    EXPECT_LT(rel_err_log(s, p), 1e-13) << "theta=" << theta;
  }
  for (double gap = 1e-2; gap >= 1e-6; gap /= 3.0) {
    const Point p = point_at(s.kind, rng.unit(), kPi - gap, s.radius_m);
    EXPECT_LT(rel_err_log(s, p), 1e-13) << "pi - " << gap;
  }
}

TEST(LogMap, MatchesOracleUpTo700RadiansInH3) {
  Rng rng(11);
  const Space s{SpaceKind::H3, 0.85};
  for (double theta = 1e-8; theta <= 700.0; theta *= 1.3) {
    const Point p = point_at(s.kind, rng.unit(), theta, s.radius_m);
    ASSERT_TRUE(std::isfinite(p.w));
    EXPECT_LT(rel_err_log(s, p), 1e-13) << "theta=" << theta;
  }
}

TEST(LogMap, BackHemisphereImageLiesOppositeAtTwoPiMinusTheta) {
  Rng rng(12);
  const Space s{SpaceKind::S3, 2.0};
  for (int i = 0; i < 50; ++i) {
    const Vec3 u = rng.unit();
    const double theta = rng.uniform(1e-3, kPi - 1e-3);
    const Point p = point_at(s.kind, u, theta, s.radius_m);
    const Vec3 back = back_log_origin(s, p);
    const Vec3 expect = -(2.0 * kPi - theta) * s.radius_m * u;
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(back[j], expect[j], 1e-12 * s.radius_m);
    // What the antipodal twin sees at −p is the front image of −p, and it
    // coincides with the back image of p shifted by π·ρ along the same ray.
    const Vec3 twin = log_origin(s, -p);
    for (int j = 0; j < 3; ++j)
      EXPECT_NEAR(back[j], twin[j] * (2.0 * kPi - theta) / (kPi - theta), 1e-11 * s.radius_m);
  }
}

TEST(LogMap, NeverProducesNaNAtTheOriginOrTheAntipode) {
  const Space s{SpaceKind::S3, 1.0};
  const Vec3 at_origin = log_origin(s, origin(s));
  const Vec3 at_antipode = log_origin(s, -origin(s));
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(at_origin[j], 0.0);
    EXPECT_TRUE(std::isfinite(at_antipode[j]));
  }
  EXPECT_NEAR(glm::length(at_antipode), kPi, 1e-15);
}

TEST(ExpLog, RoundTripAtTheOriginForRadiiFrom5cmTo1000km) {
  Rng rng(13);
  for (SpaceKind kind : kAllKinds) {
    for (int i = 0; i < 300; ++i) {
      const Space s{kind, rng.log_uniform(0.05, 1e6)};
      const double max_theta = kind == SpaceKind::S3 ? 3.0 : 20.0;
      const Vec3 v = rng.unit() * (s.radius_m * rng.log_uniform(1e-9, max_theta));
      const Point p = exp_origin(s, v);
      EXPECT_LT(off_space_error(s, p), 1e-15) << to_string(kind);
      const Vec3 back = log_origin(s, p);
      EXPECT_LT(glm::length(back - v), 1e-14 * glm::length(v) + 1e-300) << to_string(kind);
      // exp ∘ log = id as well.
      // A relative error ε in θ moves the point by about θ·ε of its size.
      const Point again = exp_origin(s, back);
      const double theta = glm::length(v) / s.radius_m;
      EXPECT_LT(glm::length(again - p), 2e-15 * (1.0 + theta) * std::max(s.radius_m, std::abs(p.w)));
    }
  }
}

TEST(ExpLog, RoundTripAtArbitraryFrames) {
  Rng rng(14);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 1.3};
    for (int i = 0; i < 200; ++i) {
      const Isometry frame = random_isometry(s, rng, 1.5);
      const Vec3 v = rng.unit() * rng.uniform(0.0, 2.5);
      const Point q = exp_at(s, frame, v);
      EXPECT_LT(glm::length(log_at(s, frame, q) - v), 1e-12);
      // The ambient version agrees on distances.
      const Point p = position(s, frame);
      const Vec4 amb = log_ambient(s, p, q);
      EXPECT_NEAR(std::sqrt(vector_form(s, amb, amb)), distance_m(s, p, q), 1e-12);
      EXPECT_LT(glm::length(exp_ambient(s, p, amb) - q), 1e-12 * std::max(1.0, std::abs(q.w)));
    }
  }
}

TEST(Distance, MatchesOracleForNearAndFarPairs) {
  Rng rng(15);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 0.9};
    for (int i = 0; i < 300; ++i) {
      const double base = kind == SpaceKind::S3 ? rng.uniform(0.0, 3.0) : rng.uniform(0.0, 8.0);
      const Point p = point_at(kind, rng.unit(), base, s.radius_m);
      double sep = rng.log_uniform(1e-9, kind == SpaceKind::S3 ? kPi - 1e-7 : 10.0);
      if (i % 10 == 0 && kind == SpaceKind::S3) sep = kPi - rng.log_uniform(1e-7, 1e-3);
      // q at distance sep from p, built in quad precision.
      const Vec3 u = rng.unit();
      const auto tp = oracle::translation(to_oracle(kind), p.x, p.y, p.z,
                                          oracle::distance_from_origin(to_oracle(kind), to_q(p), s.radius_m));
      const auto tu = oracle::translation(to_oracle(kind), u.x, u.y, u.z, sep);
      oracle::QVec4 o;
      o[3] = s.radius_m;
      const Point q = to_d(oracle::mul(oracle::mul(tp, tu), o));
      const double want = oracle::to_d(oracle::distance(to_oracle(kind), to_q(p), to_q(q), s.radius_m));
      const double got = distance_rad(s, p, q);
      // In global coordinates the distance between far H3 points cancels by
      // ~w_p·w_q (the hyperboloid model's condition number; DESIGN.md §2 keeps
      // rendering relative to the viewer for this reason). S3 and E3 have w ≤ ρ.
      const double wp = std::max(1.0, std::abs(p.w) / s.radius_m);
      const double wq = std::max(1.0, std::abs(q.w) / s.radius_m);
      EXPECT_LT(std::abs(got - want), 1e-13 * want + 1e-15 * wp * wq)
          << to_string(kind) << " sep=" << sep;
      EXPECT_EQ(got, distance_rad(s, q, p));
    }
  }
}

TEST(Distance, TriangleInequalityAndIsometryInvariance) {
  Rng rng(16);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, rng.log_uniform(0.05, 1e6)};
    for (int i = 0; i < 200; ++i) {
      const Point a = exp_origin(s, rng.unit() * s.radius_m * rng.uniform(0, 1.4));
      const Point b = exp_origin(s, rng.unit() * s.radius_m * rng.uniform(0, 1.4));
      const Point c = exp_origin(s, rng.unit() * s.radius_m * rng.uniform(0, 1.4));
      EXPECT_LE(distance_rad(s, a, c), distance_rad(s, a, b) + distance_rad(s, b, c) + 1e-12);
      const Isometry m = random_isometry(s, rng, 1.0);
      EXPECT_NEAR(distance_rad(s, m * a, m * b), distance_rad(s, a, b), 1e-12);
    }
  }
}

TEST(ContinuousLimit, CurvedSpacesApproachE3AsTheRadiusGrows) {
  // Metre-scale geometry in S3 and H3 of radius ρ departs from E3 by
  // O((d/ρ)²) relative: the error must shrink ~100× for each 10× in ρ.
  Rng rng(17);
  const Vec3 a_m = rng.unit() * 1.3;
  const Vec3 b_m = rng.unit() * 0.8;
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3}) {
    double previous = 1.0;
    for (double rho : {10.0, 100.0, 1e3, 1e4}) {
      const Space s{kind, rho};
      const Space e{SpaceKind::E3, rho};
      const double curved = distance_m(s, exp_origin(s, a_m), exp_origin(s, b_m));
      const double flat = distance_m(e, exp_origin(e, a_m), exp_origin(e, b_m));
      const double rel = std::abs(curved - flat) / flat;
      EXPECT_LT(rel, 1.0 / (rho * rho)) << to_string(kind) << " rho=" << rho;
      if (rho > 10.0 && previous > 1e-12) {
        EXPECT_LT(rel, previous / 50.0);
      }
      previous = rel;
    }
    // At 1000 km nothing at lab scale can be told apart from E3.
    const Space s{kind, 1e6};
    const Space e{SpaceKind::E3, 1e6};
    const Isometry ms = translation_m(s, a_m) * rotation(Vec3(0, 1, 0), 0.4) * translation_m(s, b_m);
    const Isometry me = translation_m(e, a_m) * rotation(Vec3(0, 1, 0), 0.4) * translation_m(e, b_m);
    // Compare the horizontal parts: w differs by d²/2ρ by construction.
    const Point ps = position(s, ms);
    const Point pe = position(e, me);
    EXPECT_LT(norm3(ps - pe), 1e-9);
  }
}

}  // namespace
}  // namespace curvlab::testing
