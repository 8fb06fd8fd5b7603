// Test helpers: conversions between the code's double types and the
// oracle's quad types, random poses, and tolerance checks.
#pragma once

#include "oracle.hpp"

#include "curvlab/geometry/isometry.hpp"

#include <cmath>
#include <random>

namespace curvlab::testing {

using geometry::Isometry;
using geometry::Point;
using geometry::Space;
using geometry::SpaceKind;
using geometry::Vec3;
using oracle::Q;

inline oracle::Kind to_oracle(SpaceKind k) {
  switch (k) {
    case SpaceKind::S3: return oracle::Kind::S3;
    case SpaceKind::E3: return oracle::Kind::E3;
    case SpaceKind::H3: return oracle::Kind::H3;
  }
  return oracle::Kind::E3;
}

inline oracle::QVec4 to_q(const Point& p) {
  oracle::QVec4 q;
  for (int i = 0; i < 4; ++i) q[i] = p[i];
  return q;
}

inline Point to_d(const oracle::QVec4& q) {
  return {oracle::to_d(q[0]), oracle::to_d(q[1]), oracle::to_d(q[2]), oracle::to_d(q[3])};
}

// Largest |a − b| over the matrix entries (oracle matrices are row-major).
inline double max_diff(const Isometry& a, const oracle::QMat4& b) {
  double d = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(a.m[c][r] - oracle::to_d(b.at(r, c))));
  return d;
}

inline double max_diff(const Isometry& a, const Isometry& b) {
  double d = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(a.m[c][r] - b.m[c][r]));
  return d;
}

inline double max_abs(const Isometry& a) {
  double d = 0.0;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) d = std::max(d, std::abs(a.m[c][r]));
  return d;
}

inline const SpaceKind kAllKinds[] = {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3};

struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(gen);
  }
  Vec3 unit() {
    while (true) {
      const Vec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
      const double n = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
      if (n > 0.1 && n <= 1.0) return v / n;
    }
  }
  // log-uniform radius in [lo, hi]
  double log_uniform(double lo, double hi) {
    return std::exp(uniform(std::log(lo), std::log(hi)));
  }
};

// A random isometry: translation by up to max_t radians, then a rotation.
inline Isometry random_isometry(const Space& s, Rng& rng, double max_t) {
  return geometry::translation_rad(s, rng.unit(), rng.uniform(0.0, max_t)) *
         geometry::rotation(rng.unit(), rng.uniform(-3.1, 3.1));
}

}  // namespace curvlab::testing
