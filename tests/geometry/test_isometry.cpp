#include "helpers.hpp"

#include "curvlab/geometry/maps.hpp"

#include <gtest/gtest.h>

namespace curvlab::testing {
namespace {

using namespace geometry;

TEST(Translation, MatchesEachSpacesClosedFormInQuadPrecision) {
  Rng rng(1);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 1.0};
    for (int i = 0; i < 200; ++i) {
      const Vec3 u = rng.unit();
      const double t = rng.uniform(-3.0, 3.0);
      const Isometry m = translation_rad(s, u, t);
      const auto o = oracle::translation(to_oracle(kind), u.x, u.y, u.z, t);
      EXPECT_LT(max_diff(m, o), 2e-15 * std::max(1.0, max_abs(m)))
          << to_string(kind) << " t=" << t;
    }
  }
}

TEST(Translation, MetresAndRadiansAgree) {
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 2.5};
    const Isometry a = translation_m(s, Vec3(0.0, 0.0, -1.0));
    const Isometry b = translation_rad(s, Vec3(0.0, 0.0, -1.0), 1.0 / 2.5);
    EXPECT_LT(max_diff(a, b), 1e-16);
    // The origin moves exactly 1 m forward.
    EXPECT_NEAR(distance_m(s, origin(s), position(s, a)), 1.0, 1e-15);
  }
}

TEST(Inverse, CompositionIdentitiesHoldForRandomMotions) {
  Rng rng(2);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, rng.log_uniform(0.05, 1e6)};
    for (int i = 0; i < 200; ++i) {
      const Isometry a = random_isometry(s, rng, 2.0);
      const Isometry b = random_isometry(s, rng, 2.0);
      const double scale = max_abs(a) * max_abs(b);
      EXPECT_LT(max_diff(inverse(s, a) * a, Isometry::identity()), 1e-14 * scale * scale);
      EXPECT_LT(max_diff(a * inverse(s, a), Isometry::identity()), 1e-14 * scale * scale);
      EXPECT_LT(max_diff(inverse(s, a * b), inverse(s, b) * inverse(s, a)), 1e-13 * scale * scale);
      // Conditioning grows with |M|² (Lorentz matrices have entries cosh t).
      EXPECT_LT(max_diff(inverse(s, inverse(s, a)), a), 1e-13 * max_abs(a) * max_abs(a));
    }
  }
}

TEST(Inverse, IsTransposeInS3AndLorentzTransposeInH3) {
  Rng rng(3);
  const Space s3{SpaceKind::S3, 1.0};
  const Space h3{SpaceKind::H3, 1.0};
  const Isometry a = random_isometry(s3, rng, 2.0);
  const Isometry b = random_isometry(h3, rng, 2.0);
  const Isometry ia = inverse(s3, a);
  const Isometry ib = inverse(h3, b);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      EXPECT_NEAR(ia.m[c][r], a.m[r][c], 1e-15);
      const double sign = ((r == 3) != (c == 3)) ? -1.0 : 1.0;
      EXPECT_NEAR(ib.m[c][r], sign * b.m[r][c], 1e-13);
    }
}

TEST(Reorthonormalize, RepairsPerturbedMatricesAndKeepsThePosition) {
  Rng rng(4);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 1.0};
    for (int i = 0; i < 100; ++i) {
      const Isometry exact = random_isometry(s, rng, 1.5);
      Isometry noisy = exact;
      for (int c = 0; c < 4; ++c)
        for (int r = 0; r < 4; ++r) noisy.m[c][r] += rng.uniform(-1e-7, 1e-7);
      if (kind == SpaceKind::E3) noisy.m[0][3] = noisy.m[1][3] = noisy.m[2][3] = 0.0;
      ASSERT_GT(isometry_error(s, noisy), 1e-9);
      const Isometry fixed = reorthonormalize(s, noisy);
      EXPECT_LT(isometry_error(s, fixed), 1e-14) << to_string(kind);
      // The position column is the noisy one projected radially onto the space.
      const Point p = position(s, fixed);
      const Point expect = normalize_point(s, noisy.m[3] * s.radius_m);
      for (int j = 0; j < 4; ++j) EXPECT_NEAR(p[j], expect[j], 1e-14 * std::max(1.0, std::abs(p.w)));
      // The repaired frame is within the noise of the exact one.
      EXPECT_LT(max_diff(fixed, exact), 1e-5 * max_abs(exact));
      // An exact isometry is left as it is.
      EXPECT_LT(max_diff(reorthonormalize(s, exact), exact), 1e-14 * max_abs(exact) * max_abs(exact));
    }
  }
}

TEST(Decompose, TranslationThenRotationRebuildsTheMotion) {
  Rng rng(5);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 0.7};
    for (int i = 0; i < 100; ++i) {
      const Isometry m = random_isometry(s, rng, 2.0);
      const Decomposition d = decompose(s, m);
      EXPECT_LT(max_diff(d.translation * rotation(d.rotation), m), 1e-13 * max_abs(m));
      EXPECT_NEAR(glm::determinant(d.rotation), 1.0, 1e-13);
    }
  }
}

}  // namespace
}  // namespace curvlab::testing
