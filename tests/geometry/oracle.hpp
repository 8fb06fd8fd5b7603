// An independent high-precision oracle for the geometry tests: per-space
// closed forms (deliberately branching on the space, unlike the code under
// test) evaluated in __float128 with libquadmath.
#pragma once

#include <quadmath.h>

#include <array>

namespace curvlab::oracle {

using Q = __float128;
enum class Kind { S3, E3, H3 };

struct QVec4 {
  std::array<Q, 4> v{};
  Q& operator[](int i) { return v[static_cast<std::size_t>(i)]; }
  Q operator[](int i) const { return v[static_cast<std::size_t>(i)]; }
};

struct QMat4 {
  std::array<std::array<Q, 4>, 4> a{};  // a[row][col]
  static QMat4 identity() {
    QMat4 m;
    for (int i = 0; i < 4; ++i) m.a[static_cast<std::size_t>(i)][static_cast<std::size_t>(i)] = 1;
    return m;
  }
  Q& at(int r, int c) { return a[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)]; }
  Q at(int r, int c) const { return a[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)]; }
};

inline QMat4 mul(const QMat4& x, const QMat4& y) {
  QMat4 m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      Q s = 0;
      for (int k = 0; k < 4; ++k) s += x.at(r, k) * y.at(k, c);
      m.at(r, c) = s;
    }
  return m;
}

inline QVec4 mul(const QMat4& x, const QVec4& p) {
  QVec4 out;
  for (int r = 0; r < 4; ++r) {
    Q s = 0;
    for (int k = 0; k < 4; ++k) s += x.at(r, k) * p[k];
    out[r] = s;
  }
  return out;
}

// Translation by t along coordinate axis i (0, 1, 2): a rotation of the
// (x_i, w) plane in S3, a boost in H3, a shear in E3.
inline QMat4 axis_translation(Kind kind, int i, Q t) {
  QMat4 m = QMat4::identity();
  switch (kind) {
    case Kind::S3:
      m.at(i, i) = cosq(t); m.at(i, 3) = sinq(t);
      m.at(3, i) = -sinq(t); m.at(3, 3) = cosq(t);
      break;
    case Kind::H3:
      m.at(i, i) = coshq(t); m.at(i, 3) = sinhq(t);
      m.at(3, i) = sinhq(t); m.at(3, 3) = coshq(t);
      break;
    case Kind::E3:
      m.at(i, 3) = t;
      break;
  }
  return m;
}

// Rotation of the xyz block taking the x axis to the unit vector u, built from
// a yaw about y followed by a pitch (spherical angles), so that translations
// along u can be formed by conjugation — a different construction from the
// code under test.
inline QMat4 rotation_x_to(Q ux, Q uy, Q uz) {
  const Q el = asinq(uy);               // elevation toward +y
  const Q az = atan2q(-uz, ux);         // azimuth from +x toward −z
  QMat4 yaw = QMat4::identity();        // about +y by az
  yaw.at(0, 0) = cosq(az); yaw.at(0, 2) = sinq(az);
  yaw.at(2, 0) = -sinq(az); yaw.at(2, 2) = cosq(az);
  QMat4 pitch = QMat4::identity();      // about +z by el
  pitch.at(0, 0) = cosq(el); pitch.at(0, 1) = -sinq(el);
  pitch.at(1, 0) = sinq(el); pitch.at(1, 1) = cosq(el);
  return mul(yaw, pitch);
}

inline QMat4 transpose(const QMat4& m) {
  QMat4 t;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t.at(r, c) = m.at(c, r);
  return t;
}

inline QMat4 translation(Kind kind, Q ux, Q uy, Q uz, Q t) {
  const Q n = sqrtq(ux * ux + uy * uy + uz * uz);
  const QMat4 r = rotation_x_to(ux / n, uy / n, uz / n);
  return mul(mul(r, axis_translation(kind, 0, t)), transpose(r));
}

// Distance from the origin in radians (per-space closed forms).
inline Q distance_from_origin(Kind kind, const QVec4& p, Q rho) {
  const Q r = sqrtq(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  switch (kind) {
    case Kind::S3:
      // Both branches well conditioned in quad: acos away from ±1, asin near.
      if (fabsq(p[3] / rho) < Q(0.5)) return acosq(p[3] / rho);
      return p[3] > 0 ? asinq(r / rho) : acosq(Q(-1)) - asinq(r / rho);
    case Kind::H3: return asinhq(r / rho);
    case Kind::E3: return r / rho;
  }
  return 0;
}

// Distance between points: move p to the origin with the inverse of the
// translation that takes the origin to p, then measure from the origin.
inline Q distance(Kind kind, const QVec4& p, const QVec4& q, Q rho) {
  const Q r = sqrtq(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  if (r == 0) return distance_from_origin(kind, q, rho);
  const Q t = distance_from_origin(kind, p, rho);
  const QMat4 back = translation(kind, p[0], p[1], p[2], -t);
  return distance_from_origin(kind, mul(back, q), rho);
}

// Azimuthal-equidistant image at the origin (metres).
inline std::array<Q, 3> log_origin(Kind kind, const QVec4& p, Q rho) {
  const Q r = sqrtq(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  const Q theta = distance_from_origin(kind, p, rho);
  const Q f = r == 0 ? Q(1) : rho * theta / r;
  return {f * p[0], f * p[1], f * p[2]};
}

inline double to_d(Q q) { return static_cast<double>(q); }

}  // namespace curvlab::oracle
