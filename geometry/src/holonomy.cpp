#include "curvlab/geometry/holonomy.hpp"

#include "curvlab/geometry/maps.hpp"

namespace curvlab::geometry {

double signed_yaw_rad(const Mat3& r) {
  const double angle = rotation_angle_rad(r);
  return rotation_axis(r).y < 0.0 ? -angle : angle;
}

HolonomyResult head_square(const Space& space, double theta_rad) {
  // Naive tracking: each local move is composed on the right, in the head's
  // own frame, so the first move's matrix ends up leftmost.
  const Isometry forward = translation_rad(space, Vec3(0, 0, -1), theta_rad);
  const Isometry left = translation_rad(space, Vec3(-1, 0, 0), theta_rad);
  const Isometry back = translation_rad(space, Vec3(0, 0, 1), theta_rad);
  const Isometry right = translation_rad(space, Vec3(1, 0, 0), theta_rad);
  HolonomyResult out;
  out.final_pose = forward * left * back * right;
  const Decomposition d = decompose(space, out.final_pose);
  out.rotation_rad = signed_yaw_rad(d.rotation);
  out.offset_rad = distance_rad(space, origin(space), position(space, out.final_pose));
  return out;
}

}  // namespace curvlab::geometry
