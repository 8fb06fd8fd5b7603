// The binocular perception model against closed forms written here
// independently, in long double:
//  - vergence toward a point straight ahead: the eye–nose–point right
//    triangle gives each eye's inward rotation atan(S(a)/T(t)), a = ipd/2ρ,
//    t = d/ρ, T = S/C (sin/tan, sinh/tanh);
//  - the tourist's perceived point: an affine image of the gnomonic (S3) or
//    Klein (H3) chart centred at the nose, ρ·xyz/w scaled by a/T(a) across
//    the eyes' axis and a/S(a) along the other two (the chart's differential
//    at an eye stretches those directions by 1/C² and 1/C, and the observer
//    puts the eyes at ±ipd/2);
//  - the native image: ρθ·xyz/|xyz|, with θ of the stick's ends from the
//    Pythagorean C(θ) = C(D)·C(L/2ρ).
#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/perception.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace curvlab::geometry;
using LD = long double;

constexpr LD kPiL = 3.141592653589793238462643383279502884L;

LD S(SpaceKind k, LD t) { return k == SpaceKind::S3 ? std::sin(t) : k == SpaceKind::H3 ? std::sinh(t) : t; }
LD C(SpaceKind k, LD t) { return k == SpaceKind::S3 ? std::cos(t) : k == SpaceKind::H3 ? std::cosh(t) : 1.0L; }
LD Cinv(SpaceKind k, LD c) { return k == SpaceKind::S3 ? std::acos(c) : std::acosh(c); }

// Oracle: vergence (radians) for a point straight ahead at d metres.
LD oracle_vergence(SpaceKind k, LD rho, LD ipd, LD d) {
  const LD a = ipd / (2 * rho), t = d / rho;
  // inward = atan2(S(a)·C(t), S(t)) per eye (tan of the eye's angle to the
  // nose line is T(t)/S(a)).
  return 2 * std::atan2(S(k, a) * C(k, t), k == SpaceKind::E3 ? t : S(k, t));
}

TEST(Vergence, S3IsZeroAtAQuarterCircleAndNegativeBeyond) {
  const double rho = 0.573, ipd = 0.063;
  const Space s3{SpaceKind::S3, rho};
  const VergenceReading at = vergence_straight_ahead(s3, ipd, rho * std::numbers::pi / 2.0);
  EXPECT_NEAR(at.vergence_rad, 0.0, 1e-15);
  EXPECT_GT(std::abs(at.tourist_distance_m), 1e10);  // seen at infinity
  for (double f : {0.55, 0.7, 0.9, 0.99}) {
    const double d = f * std::numbers::pi * rho;
    const VergenceReading r = vergence_straight_ahead(s3, ipd, d);
    EXPECT_LT(r.vergence_rad, 0.0) << f;
    EXPECT_LT(r.tourist_distance_m, 0.0) << f;  // "beyond infinity"
    EXPECT_NEAR(r.vergence_rad, static_cast<double>(oracle_vergence(SpaceKind::S3, rho, ipd, d)), 1e-14);
    EXPECT_NEAR(r.native_distance_m, d, 1e-12);
  }
  for (double f : {0.05, 0.3, 0.45}) {
    const double d = f * std::numbers::pi * rho;
    EXPECT_GT(vergence_straight_ahead(s3, ipd, d).vergence_rad, 0.0);
  }
}

TEST(Vergence, MatchesTheClosedFormInEverySpace) {
  for (SpaceKind k : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const double rho = 0.848, ipd = 0.063;
    for (double d : {0.05, 0.3, 1.0, 2.5}) {
      if (k == SpaceKind::S3 && d >= std::numbers::pi * rho) continue;
      const VergenceReading r = vergence_straight_ahead({k, rho}, ipd, d);
      const LD v = oracle_vergence(k, rho, ipd, d);
      EXPECT_NEAR(r.vergence_rad, static_cast<double>(v), 1e-14) << to_string(k) << ' ' << d;
      const LD dist = (ipd / 2.0L) / std::tan(v / 2);
      EXPECT_NEAR(r.tourist_distance_m, static_cast<double>(dist), 1e-11 * std::abs(static_cast<double>(dist)));
      // Triangulating rays 63 mm apart: relative roundoff grows like d/ipd.
      EXPECT_NEAR(r.native_distance_m, d, 1e-12 * (1.0 + d / ipd));
    }
  }
}

TEST(Vergence, TheH3TouristSeesTheWholeSpaceWithinRho) {
  const double rho = 0.848, ipd = 0.063;
  const Space h3{SpaceKind::H3, rho};
  const LD a = ipd / (2.0L * rho);
  const LD limit = rho * a / std::sinh(a);  // tourist distance as d → ∞
  double previous = 0.0;
  for (double d = 0.1; d < 40.0 * rho; d *= 1.5) {
    const VergenceReading r = vergence_straight_ahead(h3, ipd, d);
    EXPECT_GT(r.vergence_rad, 0.0);
    EXPECT_LT(r.tourist_distance_m, rho);
    EXPECT_LE(r.tourist_distance_m, static_cast<double>(limit) * (1.0 + 1e-12));
    EXPECT_GT(r.tourist_distance_m, previous);  // still ordered by distance
    previous = r.tourist_distance_m;
  }
  EXPECT_NEAR(previous, static_cast<double>(limit), 1e-9);
  EXPECT_GT(previous, 0.999 * rho);
}

// Oracle: the tourist's perceived point of q (nose at the origin, eyes on x).
glm::dvec3 oracle_tourist(SpaceKind k, LD rho, LD ipd, const Point& q) {
  const LD a = ipd / (2 * rho);
  const LD sx = k == SpaceKind::E3 ? 1.0L : a * C(k, a) / S(k, a);
  const LD syz = k == SpaceKind::E3 ? 1.0L : a / S(k, a);
  const LD w = q.w;
  return {static_cast<double>(rho * q.x / w * sx), static_cast<double>(rho * q.y / w * syz),
          static_cast<double>(rho * q.z / w * syz)};
}

TEST(Tourist, PerceivedPointsAreAnAffineImageOfTheProjectiveChart) {
  const double ipd = 0.063;
  for (SpaceKind k : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const double rho = 0.7;
    const Space space{k, rho};
    for (const Vec3 v : {Vec3(0.3, 0.1, -0.9), Vec3(-0.5, -0.2, -0.4), Vec3(0.05, 0.4, -1.2),
                         Vec3(0.7, 0.0, -0.3)}) {
      const Point q = exp_origin(space, v);
      const PerceivedPoint p =
          perceive_point(space, Isometry::identity(), eyes_from_ipd(ipd), ViewPreset::tourist, q);
      const glm::dvec3 o = oracle_tourist(k, rho, ipd, q);
      EXPECT_LT(glm::length(p.position_m - o), 1e-9 * std::max(1.0, glm::length(o)))
          << to_string(k) << " v=(" << v.x << ',' << v.y << ',' << v.z << ")";
    }
  }
}

struct StickOracle {
  LD ends_m, quarter_m, sagitta_native_m;
};

StickOracle oracle_stick(SpaceKind k, LD rho, LD length, LD D) {
  const LD t = D / rho, l = length / (2 * rho), lq = length / (4 * rho);
  const LD th_end = k == SpaceKind::E3 ? std::sqrt(t * t + l * l) : Cinv(k, C(k, t) * C(k, l));
  const LD th_q = k == SpaceKind::E3 ? std::sqrt(t * t + lq * lq) : Cinv(k, C(k, t) * C(k, lq));
  // End point in nose coordinates: ρ·(S(l), 0, −C(l)·S(t)); |xyz| = ρ·S(θ).
  const LD st = k == SpaceKind::E3 ? t : S(k, t);
  const LD sl = k == SpaceKind::E3 ? l : S(k, l);
  const LD cl = C(k, l);
  const LD r = std::sqrt(sl * sl + cl * cl * st * st);
  const LD z_end = -rho * th_end * cl * st / r;
  return {rho * th_end, rho * th_q, -D - z_end};
}

TEST(Stick, AGeodesicStickIsStraightForTheTouristAndBowedForTheNative) {
  const double ipd = 0.063, length = 1.0, D = 1.0;
  for (SpaceKind k : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const double rho = k == SpaceKind::S3 ? 0.573 : 0.848;
    const Space space{k, rho};
    BentStick stick;
    stick.length_m = length;
    const StickPerception tourist = perceive_stick(space, stick, D, eyes_from_ipd(ipd), ViewPreset::tourist);
    const StickPerception native = perceive_stick(space, stick, D, eyes_from_ipd(ipd), ViewPreset::native);
    const StickOracle o = oracle_stick(k, rho, length, D);
    // Zero up to the roundoff of triangulating nearly parallel rays (in S3 at
    // D = 1 m > ρπ/2 they even diverge and the stick is seen behind the eyes).
    EXPECT_NEAR(tourist.perceived_sagitta_m, 0.0, 1e-10) << to_string(k);
    EXPECT_NEAR(native.perceived_sagitta_m, static_cast<double>(o.sagitta_native_m), 1e-12) << to_string(k);
    // All perceived tourist points on one straight line.
    const Vec3 a = tourist.perceived_m[0], b = tourist.perceived_m[4];
    for (const Vec3& p : tourist.perceived_m) {
      const Vec3 ab = glm::normalize(b - a);
      EXPECT_LT(glm::length((p - a) - glm::dot(p - a, ab) * ab), 1e-10);
    }
    EXPECT_NEAR(native.distances_m[0], static_cast<double>(o.ends_m), 1e-12);
    EXPECT_NEAR(native.distances_m[4], static_cast<double>(o.ends_m), 1e-12);
    EXPECT_NEAR(native.distances_m[1], static_cast<double>(o.quarter_m), 1e-12);
    EXPECT_NEAR(native.distances_m[2], D, 1e-12);
    if (k == SpaceKind::H3) {
      EXPECT_GT(native.perceived_sagitta_m, 0.01);  // toward the viewer
    } else if (k == SpaceKind::S3) {
      EXPECT_LT(native.perceived_sagitta_m, -0.01);  // away
    } else {
      EXPECT_NEAR(native.perceived_sagitta_m, 0.0, 1e-12);
    }
    // One eye shut: no disparity, nothing to see bowed.
    EXPECT_EQ(perceive_stick(space, stick, D, eyes_from_ipd(ipd), ViewPreset::monocular).perceived_sagitta_m, 0.0);
  }
}

TEST(Stick, AStickBentInFlatSpaceIsSeenWithItsTrueBend) {
  const Space e3{SpaceKind::E3, 1.0};
  BentStick stick;
  stick.length_m = 1.0;
  for (double h : {-0.03, 0.02}) {
    stick.sagitta_m = h;
    for (ViewPreset m : {ViewPreset::tourist, ViewPreset::native})
      EXPECT_NEAR(perceive_stick(e3, stick, 1.2, eyes_from_ipd(0.063), m).perceived_sagitta_m, h, 1e-12);
  }
}

}  // namespace
