#include "curvlab/geometry/maps.hpp"

#include <cmath>
#include <numbers>

namespace curvlab::geometry {

double distance_from_origin_rad(const Space& space, const Point& p) {
  const double r = norm3(p);
  return space.arc(r / space.radius_m, p.w / space.radius_m);
}

double distance_rad(const Space& space, const Point& p, const Point& q) {
  const double two_rho = 2.0 * space.radius_m;
  const Vec4 d = p - q;
  const Vec4 s = p + q;
  // g(d,d) ≥ 0 for two points of the space; |g(s,s)| only matters in S3,
  // where it is |p+q|², the chord to the antipode of q.
  const double half_chord = std::sqrt(std::max(0.0, vector_form(space, d, d))) / two_rho;
  const double half_anti = std::sqrt(std::abs(vector_form(space, s, s))) / two_rho;
  return 2.0 * space.arc(half_chord, half_anti);
}

Point exp_origin(const Space& space, const Vec3& v) {
  const double theta = glm::length(v) / space.radius_m;
  const double f = space.sinc(theta);
  return {f * v.x, f * v.y, f * v.z, space.radius_m * space.C(theta)};
}

Vec3 log_origin(const Space& space, const Point& q) {
  double out[3];
  log_origin_scalar<double>(space.kind, q.x, q.y, q.z, q.w, space.radius_m, out);
  return {out[0], out[1], out[2]};
}

Vec3 back_log_origin(const Space& space, const Point& q) {
  const Vec3 xyz(q.x, q.y, q.z);
  const double r = norm3(xyz);
  const double theta = space.arc(r / space.radius_m, q.w / space.radius_m);
  const double back = 2.0 * std::numbers::pi - theta;
  if (r == 0.0) return Vec3(0.0, 0.0, space.radius_m * back);
  return (-space.radius_m * back / r) * xyz;
}

Point exp_at(const Space& space, const Isometry& frame, const Vec3& v_m) {
  return frame * exp_origin(space, v_m);
}

Vec3 log_at(const Space& space, const Isometry& frame, const Point& q) {
  return log_origin(space, inverse(space, frame) * q);
}

Point exp_ambient(const Space& space, const Point& p, const Vec4& v_m) {
  const Isometry t = translation_to(space, p);
  const Vec4 local = inverse(space, t).m * v_m;
  return t * exp_origin(space, Vec3(local.x, local.y, local.z));
}

Vec4 log_ambient(const Space& space, const Point& p, const Point& q) {
  const Isometry t = translation_to(space, p);
  const Vec3 local = log_origin(space, inverse(space, t) * q);
  return t.m * Vec4(local, 0.0);
}

Point geodesic_lerp(const Space& space, const Point& p, const Point& q, double f) {
  const Vec4 v = log_ambient(space, p, q);
  return exp_ambient(space, p, f * v);
}

Point normalize_point(const Space& space, const Point& p) {
  // One formula for all three: P(p,p) = w² in E3, so E3 scales by ρ/w.
  const double n = std::sqrt(point_form(space, p, p));
  return p * (space.radius_m / n);
}

}  // namespace curvlab::geometry
