// The scripted headset's eyes (CURVLAB_TEST_XR_GAZE, documented at the top of
// runtime.cpp): which eye-tracking extensions the runtime offers
// (XR_EXT_eye_gaze_interaction's combined gaze, XR_FB_eye_tracking_social's
// per-eye gaze) and where the eyes look, as pure functions of the head's
// pose, so a test can compute the same rays on its own.
#pragma once

#include "script.hpp"

#include <array>
#include <optional>
#include <string>

namespace curvlab::test_runtime {

inline constexpr const char* kEyeGazeProfile = "/interaction_profiles/ext/eye_gaze_interaction";
inline constexpr const char* kEyeGazePose = "/user/eyes_ext/input/gaze_ext/pose";

// CURVLAB_TEST_XR_GAZE: KIND:TARGET[:LEFT,RIGHT] with KIND both, per_eye or
// combined; TARGET fixate=X,Y,Z (STAGE metres) or vergence=DEGREES; then
// the per-eye confidences (0–1, default 1). Unset: nullopt and no error; a
// malformed value: nullopt and `error` naming the variable.
std::optional<GazeScript> read_gaze_script(std::string& error);

// Per-eye gaze poses in STAGE for a head pose: each at its eye (±IPD/2 along
// the head's x axis, as the views), looking along its −Z axis.
std::array<Pose, 2> eye_gaze_poses(const GazeScript& gaze, const Pose& head);
// The combined gaze: from the midpoint of the eyes (the head pose's
// position) toward the fixated point, or along the head's forward direction.
Pose combined_gaze_pose(const GazeScript& gaze, const Pose& head);

}  // namespace curvlab::test_runtime
