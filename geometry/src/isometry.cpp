#include "curvlab/geometry/isometry.hpp"

#include <algorithm>
#include <cmath>

namespace curvlab::geometry {
namespace {

Vec4 col(const Isometry& iso, int i) { return iso.m[i]; }

}  // namespace

Isometry translation_rad(const Space& space, const Vec3& u, double t) {
  const double c = space.C(t);
  const double s = space.S(t);
  const double k = space.k();
  Isometry iso;
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) iso.m[j][i] += (c - 1.0) * u[i] * u[j];
    iso.m[3][j] = s * u[j];        // column w, row j
    iso.m[j][3] = -k * s * u[j];   // column j, row w
  }
  iso.m[3][3] = c;
  return iso;
}

Isometry translation_m(const Space& space, const Vec3& v_m) {
  const double len = glm::length(v_m);
  if (len == 0.0) return Isometry::identity();
  return translation_rad(space, v_m / len, len / space.radius_m);
}

Isometry rotation(const Vec3& a, double angle) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  const double t = 1.0 - c;
  Mat3 r;
  // Rodrigues' formula, column-major: r[col][row].
  r[0] = Vec3(t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y);
  r[1] = Vec3(t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x);
  r[2] = Vec3(t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c);
  return rotation(r);
}

Isometry rotation(const Mat3& r) {
  Isometry iso;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) iso.m[j][i] = r[j][i];
  return iso;
}

Isometry inverse(const Space& space, const Isometry& iso) {
  const double k = space.k();
  const Vec4 p = col(iso, 3);
  // Row forms as 4-vectors: f(q) = dot(f, q).
  const Vec4 row3(k * p.x, k * p.y, k * p.z, p.w);
  Isometry inv;
  for (int i = 0; i < 3; ++i) {
    const Vec4 e = col(iso, i);
    const Vec4 gi(e.x, e.y, e.z, k * e.w);
    const Vec4 row = gi - vector_form(space, e, p) * row3;
    for (int j = 0; j < 4; ++j) inv.m[j][i] = row[j];
  }
  for (int j = 0; j < 4; ++j) inv.m[j][3] = row3[j];
  return inv;
}

Isometry reorthonormalize(const Space& space, const Isometry& iso) {
  Isometry out = iso;
  Vec4 p = col(iso, 3);
  // Unit position: P(p,p) = 1. In E3 this sets w = 1 and leaves xyz free.
  p /= std::sqrt(point_form(space, p, p));
  out.m[3] = p;
  for (int i = 0; i < 3; ++i) {
    Vec4 e = col(iso, i);
    // Make e tangent at p (P(e, p) = 0); in E3 this zeroes e_w.
    e -= point_form(space, e, p) * p;
    for (int j = 0; j < i; ++j) {
      const Vec4 f = out.m[j];
      e -= vector_form(space, e, f) * f;
    }
    // A second pass (modified Gram–Schmidt, "twice is enough") removes what
    // cancellation left of the first.
    e -= point_form(space, e, p) * p;
    for (int j = 0; j < i; ++j) {
      const Vec4 f = out.m[j];
      e -= vector_form(space, e, f) * f;
    }
    e /= std::sqrt(vector_form(space, e, e));
    out.m[i] = e;
  }
  return out;
}

double isometry_error(const Space& space, const Isometry& iso) {
  const Vec4 p = col(iso, 3);
  double err = std::abs(point_form(space, p, p) - 1.0);
  for (int i = 0; i < 3; ++i) {
    const Vec4 e = col(iso, i);
    err = std::max(err, std::abs(point_form(space, e, p)));
    for (int j = i; j < 3; ++j) {
      const double target = (i == j) ? 1.0 : 0.0;
      err = std::max(err, std::abs(vector_form(space, e, col(iso, j)) - target));
    }
  }
  return err;
}

Point position(const Space& space, const Isometry& iso) {
  return iso.m * origin(space);
}

Isometry translation_to(const Space& space, const Point& p) {
  const double rho = space.radius_m;
  const Vec3 xyz(p.x, p.y, p.z);
  const double r = norm3(xyz);
  if (r == 0.0) return Isometry::identity();
  const double t = space.arc(r / rho, p.w / rho);
  return translation_rad(space, xyz / r, t);
}

Decomposition decompose(const Space& space, const Isometry& iso) {
  Decomposition d;
  d.translation = translation_to(space, position(space, iso));
  const Isometry r = inverse(space, d.translation) * iso;
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) d.rotation[j][i] = r.m[j][i];
  return d;
}

double rotation_angle_rad(const Mat3& r) {
  // atan2 of (|axis·sin|, cos) stays accurate for tiny angles, where
  // acos((trace−1)/2) would lose half the digits.
  const Vec3 s(r[1][2] - r[2][1], r[2][0] - r[0][2], r[0][1] - r[1][0]);
  const double trace = r[0][0] + r[1][1] + r[2][2];
  return std::atan2(0.5 * glm::length(s), 0.5 * (trace - 1.0));
}

Vec3 rotation_axis(const Mat3& r) {
  const Vec3 s(r[1][2] - r[2][1], r[2][0] - r[0][2], r[0][1] - r[1][0]);
  const double len = glm::length(s);
  if (len > 1e-300) return s / len;
  // Angle 0 or π: take the column of (R + I) with the largest norm.
  const Mat3 a = r + Mat3(1.0);
  Vec3 best(1.0, 0.0, 0.0);
  double best_len = 0.0;
  for (int j = 0; j < 3; ++j) {
    const double l = glm::length(a[j]);
    if (l > best_len) { best_len = l; best = a[j]; }
  }
  return best_len > 1e-12 ? best / best_len : Vec3(1.0, 0.0, 0.0);
}

}  // namespace curvlab::geometry
