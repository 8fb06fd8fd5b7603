// Distances, exponential and logarithm (azimuthal-equidistant) maps, and the
// S3 back-hemisphere image. Robust forms from DESIGN.md §2: never acos/acosh
// of a ratio near 1 (the paper's shader formulas, section "Native-inhabitant
// view vs. tourist view", lose precision there — "correct near north pole,
// but not near south pole").
#pragma once

#include "curvlab/geometry/isometry.hpp"

#include <cmath>

namespace curvlab::geometry {

// Geodesic distance from the origin in radians:
// S3 atan2(|xyz|, w); E3 |xyz|/ρ; H3 asinh(|xyz|/ρ).
double distance_from_origin_rad(const Space& space, const Point& p);

// Geodesic distance between two points in radians, from chords:
// S3 2·atan2(|p−q|, |p+q|); E3 |p−q|/ρ; H3 2·asinh(√g(p−q,p−q) / 2ρ).
double distance_rad(const Space& space, const Point& p, const Point& q);
inline double distance_m(const Space& space, const Point& p, const Point& q) {
  return distance_rad(space, p, q) * space.radius_m;
}

// Exponential map at the origin: tangent vector v (metres) → point
// (sinc(θ)·v, ρ·C(θ)), θ = |v|/ρ.
Point exp_origin(const Space& space, const Vec3& v_m);

// Logarithm at the origin, the azimuthal-equidistant image (metres):
// q' = ρθ·xyz/|xyz|. The exact S3 antipode has no direction; it maps to
// distance ρπ straight ahead (−z), never NaN.
Vec3 log_origin(const Space& space, const Point& q);

// S3 only: the image of q seen through the antipode, at distance 2π − θ in the
// opposite direction: −ρ(2π − θ)·xyz/|xyz| (the paper's (π+θ)/sin θ factor
// holds only for the antipodal twin's coordinates −q).
Vec3 back_log_origin(const Space& space, const Point& q);

// The same log map for any floating-point type (float for the GPU-precision
// comparison, double above): the formula lives once. The renderer's GLSL
// carries a copy, checked against this one by a test.
template <class T>
void log_origin_scalar(SpaceKind kind, T x, T y, T z, T w, T rho, T out[3]) {
  using std::abs, std::atan2, std::asinh, std::sqrt, std::max;
  const T m = max(max(abs(x), abs(y)), abs(z));
  T r = T(0);
  if (m > T(0)) {
    const T a = x / m, b = y / m, c = z / m;  // squares of x may overflow
    r = m * sqrt(a * a + b * b + c * c);
  }
  T theta = r / rho;  // E3
  if (kind == SpaceKind::S3) theta = atan2(r / rho, w / rho);
  if (kind == SpaceKind::H3) theta = asinh(r / rho);
  if (r == T(0)) {
    out[0] = out[1] = T(0);
    out[2] = theta == T(0) ? T(0) : -rho * theta;
    return;
  }
  // ρθ/r, grouped so that neither ρθ nor the result overflows needlessly.
  const T f = (theta / r) * rho;
  out[0] = f * x;
  out[1] = f * y;
  out[2] = f * z;
}

// Maps at an arbitrary point given by a frame (an isometry whose column 3 is
// the point): the tangent vector is expressed in that frame's axes.
Point exp_at(const Space& space, const Isometry& frame, const Vec3& v_m);
Vec3 log_at(const Space& space, const Isometry& frame, const Point& q);

// Maps at an arbitrary point p with tangent vectors as ambient 4-vectors
// (metres), parallel-transported frame from the origin.
Point exp_ambient(const Space& space, const Point& p, const Vec4& v_m);
Vec4 log_ambient(const Space& space, const Point& p, const Point& q);

// The point at parameter f ∈ [0, 1] on the geodesic from p to q.
Point geodesic_lerp(const Space& space, const Point& p, const Point& q, double f);

// Projects an approximate point back onto the space (for user input and for
// drift) by the radial rescaling ρ/√P(p,p) (in E3: the projective ρ/w).
Point normalize_point(const Space& space, const Point& p);

}  // namespace curvlab::geometry
