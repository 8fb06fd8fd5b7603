// Small pieces of the cloth's 2-D space form shared by billiards.cpp and
// billiards_system.cpp. Cloth points and vectors are (x, z, w).
#pragma once

#include "curvlab/geometry/billiards.hpp"

#include <cmath>

namespace curvlab::geometry::billiards::detail {

// Below these the contact point does not slip, the ball does not move, and
// it does not spin.
inline constexpr double kSlipTolerance_m_s = 1e-9;
inline constexpr double kStillSpeed_m_s = 1e-12;
inline constexpr double kStillSpin_rad_s = 1e-12;

inline double point_form(double k, const glm::dvec3& a, const glm::dvec3& b) {
  return k * (a.x * b.x + a.y * b.y) + a.z * b.z;
}
inline double vector_form(double k, const glm::dvec3& a, const glm::dvec3& b) {
  return a.x * b.x + a.y * b.y + k * a.z * b.z;
}

// Distance in radians from chords (never an acos of a ratio near 1).
inline double distance_rad(const Space& space, const glm::dvec3& p, const glm::dvec3& q) {
  const glm::dvec3 d = p - q;
  const double chord = std::sqrt(std::max(0.0, vector_form(space.k(), d, d)));
  return 2.0 * space.S_inv(chord / (2.0 * space.radius_m));
}

// The unit tangent at p toward q (q ≠ p).
inline glm::dvec3 direction(const Space& space, const glm::dvec3& p, const glm::dvec3& q) {
  const double t = distance_rad(space, p, q);
  glm::dvec3 u = (q - space.C(t) * p) / (space.radius_m * space.S(t));
  // Remove what rounding left along p, and renormalise.
  const double rho2 = space.radius_m * space.radius_m;
  u -= (point_form(space.k(), u, p) / rho2) * p;
  return u / std::sqrt(vector_form(space.k(), u, u));
}

// Translation by t radians along the unit tangent direction u (x, z) at the
// origin: x_u' = C x_u + S w, w' = −k S x_u + C w.
inline Frame translation(double k, double C, double S, Vec2 u) {
  Frame m{1.0};
  const double ux = u.x, uz = u.y;
  // m[col][row]
  m[0][0] = 1.0 + (C - 1.0) * ux * ux;
  m[0][1] = (C - 1.0) * ux * uz;
  m[0][2] = -k * S * ux;
  m[1][0] = (C - 1.0) * uz * ux;
  m[1][1] = 1.0 + (C - 1.0) * uz * uz;
  m[1][2] = -k * S * uz;
  m[2][0] = S * ux;
  m[2][1] = S * uz;
  m[2][2] = C;
  return m;
}

// An element of the cloth's isometry algebra: translation rates a (x) and
// b (z) in radians, rotation c about the vertical.
struct Generator {
  double a = 0.0, b = 0.0, c = 0.0;
};
inline Generator commutator(double k, const Generator& x, const Generator& y) {
  // [X, Y] of two translations is a rotation k(a_x b_y − b_x a_y); of a
  // rotation and a translation, a turned translation.
  return {y.c * x.b - x.c * y.b, x.c * y.a - y.c * x.a, k * (x.a * y.b - x.b * y.a)};
}
inline Mat3 matrix(double k, const Generator& g) {
  Mat3 m{0.0};
  m[0][1] = g.c;
  m[0][2] = -k * g.a;
  m[1][0] = -g.c;
  m[1][2] = -k * g.b;
  m[2][0] = g.a;
  m[2][1] = g.b;
  return m;
}
// exp(X) = I + f1 X + f2 X², with X³ = −λX, λ = c² + k(a² + b²).
inline Mat3 exp(double k, const Generator& g) {
  const Mat3 x = matrix(k, g);
  const double lambda = g.c * g.c + k * (g.a * g.a + g.b * g.b);
  double f1 = 1.0, f2 = 0.5;
  if (std::abs(lambda) < 1e-6) {
    f1 = 1.0 - lambda / 6.0 + lambda * lambda / 120.0;
    f2 = 0.5 - lambda / 24.0 + lambda * lambda / 720.0;
  } else if (lambda > 0.0) {
    const double s = std::sqrt(lambda);
    f1 = std::sin(s) / s;
    f2 = (1.0 - std::cos(s)) / lambda;
  } else {
    const double s = std::sqrt(-lambda);
    f1 = std::sinh(s) / s;
    f2 = (std::cosh(s) - 1.0) / -lambda;
  }
  return Mat3{1.0} + f1 * x + f2 * (x * x);
}

// Metric-aware Gram–Schmidt that keeps the position column.
inline Frame reorthonormalize(double k, const Frame& f) {
  Frame out = f;
  glm::dvec3 p = f[2];
  p /= std::sqrt(point_form(k, p, p));
  out[2] = p;
  for (int i = 0; i < 2; ++i) {
    glm::dvec3 e = f[i];
    for (int pass = 0; pass < 2; ++pass) {
      e -= point_form(k, e, p) * p;
      for (int j = 0; j < i; ++j) e -= vector_form(k, e, out[j]) * out[j];
    }
    out[i] = e / std::sqrt(vector_form(k, e, e));
  }
  return out;
}

// The contact point's slip velocity u = v + w × (−R up), tangential part.
inline Vec2 slip(const Parameters& p, Vec2 v, const glm::dvec3& w) {
  return {v.x + p.radius_m * w.z, v.y - p.radius_m * w.x};
}

}  // namespace curvlab::geometry::billiards::detail
