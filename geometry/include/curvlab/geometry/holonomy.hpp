// The paper's head-square under naive tracking (section "Headset tracking and
// body coherence: the problem"): the head moves d forward (−z), d left (−x),
// d back (+z) and d right (+x), each move applied in the head's own frame.
// In the lab it returns home; in S3 and H3 it comes back rotated by ≈ kθ²
// (θ = d/ρ) and offset by ≈ θ³/√2.
#pragma once

#include "curvlab/geometry/isometry.hpp"

namespace curvlab::geometry {

struct HolonomyResult {
  Isometry final_pose;
  // Signed rotation about +y (counter-clockwise seen from above positive).
  double rotation_rad = 0.0;
  // Geodesic distance from the start to the final head position.
  double offset_rad = 0.0;
};

HolonomyResult head_square(const Space& space, double theta_rad);

// Signed angle of a rotation about +y: the full rotation angle, signed by the
// axis's y component (counter-clockwise seen from above positive).
double signed_yaw_rad(const Mat3& rotation);

}  // namespace curvlab::geometry
