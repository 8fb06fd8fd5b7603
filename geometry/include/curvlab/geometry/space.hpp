// The three isotropic spaces as one value type, and the generalized
// trigonometric functions that let one code path serve all of them.
//
// Conventions (DESIGN.md §2; paper, "Definitions and notation" and
// "Euclidean radians"): points are 4-vectors in metres.
//   S3: x²+y²+z²+w² = ρ²        H3: x²+y²+z²−w² = −ρ², w > 0
//   E3: the hyperplane w = ρ.
// Written with the curvature sign k = +1 | 0 | −1 all three are
//   k(x²+y²+z²) + w² = ρ²,
// which is the "point form" P below. Tangent vectors use the "vector form"
// g(u,v) = u·v (xyz) + k u_w v_w, positive definite on every tangent space.
#pragma once

#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <optional>
#include <string>
#include <string_view>

namespace curvlab::geometry {

enum class SpaceKind { S3, E3, H3 };

std::string_view to_string(SpaceKind kind);
std::optional<SpaceKind> parse_space_kind(std::string_view text);

// A space is a value, never a global: {kind, radius in metres}.
struct Space {
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 1.0;

  // Curvature sign k: +1 (S3), 0 (E3), −1 (H3).
  [[nodiscard]] double k() const;
  // Generalized cosine and sine of a distance in radians:
  // C = cos | 1 | cosh, S = sin | t | sinh.
  [[nodiscard]] double C(double t_rad) const;
  [[nodiscard]] double S(double t_rad) const;
  // S(t)/t, accurate near t = 0 (series), 1 in E3.
  [[nodiscard]] double sinc(double t_rad) const;
  // t/S(t), the azimuthal-equidistant factor, accurate near t = 0.
  [[nodiscard]] double inv_sinc(double t_rad) const;
  // The inverse of S: asin | identity | asinh. In S3 the argument is clamped
  // to [−1, 1] (a contract: callers pass values from points on the sphere).
  [[nodiscard]] double S_inv(double s) const;
  // The inverse of C on [0, ∞): acos | 0 | acosh (argument clamped).
  [[nodiscard]] double C_inv(double c) const;
  // The angle t ≥ 0 with S(t) = s and C(t) = c (both already divided by ρ,
  // s ≥ 0): S3 atan2(s, c), which is well conditioned over the whole sphere
  // (acos of a ratio near ±1 is not); E3 s; H3 asinh(s), which never
  // overflows where sinh t is finite. c only decides the S3 hemisphere.
  [[nodiscard]] double arc(double s, double c) const;

  [[nodiscard]] bool is_compact() const { return kind == SpaceKind::S3; }
};

using Point = glm::dvec4;  // metres, on the space (see the forms above)
using Vec3 = glm::dvec3;
using Vec4 = glm::dvec4;

// P(a, b) = k a_xyz·b_xyz + a_w b_w. Points satisfy P(p, p) = ρ².
double point_form(const Space& space, const Vec4& a, const Vec4& b);
// g(a, b) = a_xyz·b_xyz + k a_w b_w: the metric on tangent vectors and on
// differences of points (chords).
double vector_form(const Space& space, const Vec4& a, const Vec4& b);

// The origin (0, 0, 0, ρ).
Point origin(const Space& space);

// How far p is from lying on the space, relative to ρ²: |P(p,p) − ρ²| / ρ²,
// plus, in H3, whether w > 0 (returns +∞ on the wrong sheet).
double off_space_error(const Space& space, const Point& p);

// |(x, y, z)| without overflow or underflow of the squares: far H3 points
// have coordinates near sinh θ ≈ 1e300, whose squares overflow double.
double norm3(double x, double y, double z);
inline double norm3(const Vec4& p) { return norm3(p.x, p.y, p.z); }
inline double norm3(const Vec3& v) { return norm3(v.x, v.y, v.z); }

// Fuzzy comparison with a stated magnitude: |a − b| ≤ tol · max(1, magnitude).
bool nearly_equal(double a, double b, double tol, double magnitude = 1.0);

}  // namespace curvlab::geometry
