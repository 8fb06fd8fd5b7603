// The lab volume: where a tracked device, a touched corner or the physical
// table can be. No lab is larger than 100 m in any direction from its
// tracking origin, so a coordinate beyond that (1e308, inf, NaN) is a broken
// file or a broken runtime, never a participant: readers refuse it naming
// the file, line and field (docs/tracking.md, "Trajectory files";
// docs/devices.md, "Physical-table calibration"), and the session stores a
// pose source's such pose as lost tracking (docs/runner.md).
#pragma once

#include "curvlab/geometry/tracking.hpp"

#include <cmath>

namespace curvlab::harness {

// The largest |x|, |y| or |z| of a lab position, metres.
inline constexpr double kLabBound_m = 100.0;

// A lab coordinate (metres) that is finite and within the lab volume.
inline bool within_lab(double coordinate_m) {
  return std::isfinite(coordinate_m) && std::abs(coordinate_m) <= kLabBound_m;
}

// A pose source's pose as the session may use it: a position that is not
// finite or lies outside the lab volume is lost (valid false, the position at
// the origin), an orientation that is not a finite unit quaternion (±1 %) is
// lost too (orientation_valid false, the identity). What is left tracked is
// unchanged, so a sound frame passes through as it came.
inline geometry::LabPose possible_pose(geometry::LabPose pose) {
  const auto& p = pose.position_m;
  const auto& q = pose.orientation;
  const double norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  const bool position_ok = within_lab(p.x) && within_lab(p.y) && within_lab(p.z);
  const bool orientation_ok = std::isfinite(norm) && std::abs(norm - 1.0) <= 0.01;
  if (position_ok && orientation_ok) return pose;
  const bool orientation_tracked = (pose.valid || pose.orientation_valid) && orientation_ok;
  pose.valid = false;
  pose.orientation_valid = orientation_tracked;
  if (!position_ok) pose.position_m = geometry::Vec3(0.0);
  if (!orientation_ok) pose.orientation = geometry::Quat(1.0, 0.0, 0.0, 0.0);
  return pose;
}

}  // namespace curvlab::harness
