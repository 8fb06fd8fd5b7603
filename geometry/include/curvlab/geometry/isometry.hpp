// Isometries of S3, E3 and H3 as dimensionless 4×4 matrices (column vectors,
// composition right to left): O(4), the Euclidean group with translations in
// Euclidean radians, and O(3,1) (paper, "Euclidean radians"). One code path
// serves all three spaces through Space::C, Space::S and Space::k.
#pragma once

#include "curvlab/geometry/space.hpp"

#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>

namespace curvlab::geometry {

using Mat4 = glm::dmat4;
using Mat3 = glm::dmat3;

// A rigid motion. Column 3 is the image of the origin divided by ρ; columns
// 0–2 are the images of the x, y, z unit tangent vectors at the origin.
struct Isometry {
  Mat4 m{1.0};

  static Isometry identity() { return {}; }
  Isometry operator*(const Isometry& rhs) const { return {m * rhs.m}; }
  Point operator*(const Point& p) const { return m * p; }
};

// Translation by t radians along the unit tangent direction u at the origin:
//   x_u' = C x_u + S w,  w' = −k S x_u + C w  (DESIGN.md §2).
Isometry translation_rad(const Space& space, const Vec3& unit_dir, double t_rad);
// Translation by the tangent vector v given in metres (t = |v| / ρ).
Isometry translation_m(const Space& space, const Vec3& v_m);
// Rotation about the origin, axis through the origin (right-handed).
Isometry rotation(const Vec3& unit_axis, double angle_rad);
// Rotation about the origin from a 3×3 rotation matrix.
Isometry rotation(const Mat3& r);

// Inverse without a general matrix inversion: the rows of M⁻¹ are the forms
// dual to M's frame (position p = column 3, tangent e_i = columns 0–2):
//   row_3 = P(p, ·),  row_i = g(e_i, ·) − g(e_i, p) P(p, ·).
// This is the transpose in S3, J Mᵀ J in H3 and [Rᵀ, −Rᵀt] in E3.
Isometry inverse(const Space& space, const Isometry& iso);

// Metric-aware Gram–Schmidt that keeps the position: column 3 is rescaled
// back onto the space, then columns 0–2 are made tangent there and
// g-orthonormal, in order x, y, z. Right-handedness is preserved.
Isometry reorthonormalize(const Space& space, const Isometry& iso);

// Departure from the isometry group: the largest of |P(p,p) − 1|, |P(p, e_i)|
// and |g(e_i, e_j) − δ_ij| over the frame (dimensionless).
double isometry_error(const Space& space, const Isometry& iso);

// The image of the origin, in metres.
Point position(const Space& space, const Isometry& iso);

// The translation along the geodesic from the origin to p (no rotation
// relative to parallel transport). p must lie on the space; in S3 it must not
// be the antipode of the origin.
Isometry translation_to(const Space& space, const Point& p);

// M = T · R, T = translation_to(position), R a rotation about the origin.
struct Decomposition {
  Isometry translation;
  Mat3 rotation{1.0};
};
Decomposition decompose(const Space& space, const Isometry& iso);

// Angle of a rotation matrix (0…π) and its unit axis (x when the angle is 0).
double rotation_angle_rad(const Mat3& r);
Vec3 rotation_axis(const Mat3& r);

}  // namespace curvlab::geometry
