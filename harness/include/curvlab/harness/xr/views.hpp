// Lab-space poses and asymmetric fields of view as curvlab uses them, and
// their conversion from OpenXR's XrPosef/XrFovf (STAGE space: metres, y up,
// −z forward, the same frame as DESIGN.md §2).
#pragma once

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include <openxr/openxr.h>

namespace curvlab::harness::xr {

// A pose as the runtime reports it in STAGE space, before curvlab adds what
// it knows of tracking (geometry::LabPose, with its validity flags; see
// to_geometry in stereo.hpp).
struct StagePose {
  glm::dvec3 position_m{0.0};
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};  // glm order: w, x, y, z
};

// Angles of the four frustum sides from the view direction (OpenXR's
// convention: left and down are negative for a centred eye).
struct AsymmetricFov {
  double left_rad = 0.0;
  double right_rad = 0.0;
  double up_rad = 0.0;
  double down_rad = 0.0;
};

// XrQuaternionf stores x, y, z, w; glm::dquat's constructor takes w first —
// the conversion is the one place that order is handled.
inline StagePose to_stage_pose(const XrPosef& pose) {
  return {glm::dvec3(pose.position.x, pose.position.y, pose.position.z),
          glm::normalize(glm::dquat(pose.orientation.w, pose.orientation.x, pose.orientation.y,
                                    pose.orientation.z))};
}

inline XrPosef to_xr_pose(const StagePose& pose) {
  XrPosef out{};
  out.orientation = {static_cast<float>(pose.orientation.x), static_cast<float>(pose.orientation.y),
                     static_cast<float>(pose.orientation.z), static_cast<float>(pose.orientation.w)};
  out.position = {static_cast<float>(pose.position_m.x), static_cast<float>(pose.position_m.y),
                  static_cast<float>(pose.position_m.z)};
  return out;
}

inline AsymmetricFov to_fov(const XrFovf& fov) {
  return {fov.angleLeft, fov.angleRight, fov.angleUp, fov.angleDown};
}

// Tangents of the frustum sides at unit distance: the l, r, b, t of an
// off-axis perspective projection at near = 1.
struct FrustumTangents {
  double left = 0.0, right = 0.0, down = 0.0, up = 0.0;
};

FrustumTangents tangents(const AsymmetricFov& fov);

}  // namespace curvlab::harness::xr
