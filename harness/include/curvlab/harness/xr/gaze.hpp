// Eye tracking through OpenXR (DESIGN.md §6): where the runtime offers it,
// the combined gaze of XR_EXT_eye_gaze_interaction (an action-based pose,
// /user/eyes_ext/input/gaze_ext/pose of
// /interaction_profiles/ext/eye_gaze_interaction) and the per-eye gaze of
// XR_FB_eye_tracking_social (xrGetEyeGazesFB, a pose and a confidence per
// eye), located every frame at its predicted display time in STAGE. From the
// two eyes' rays comes the vergence the perception model reasons about
// (geometry/human_vision.hpp): the measured counterpart of the vergence
// demand stored in each onset's `percept`.
#pragma once

#include "curvlab/harness/io/gaze.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/instance.hpp"
#include "curvlab/harness/xr/views.hpp"

#include <openxr/openxr.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::xr {

namespace io = harness::io;

inline constexpr const char* kEyeGazeProfile = "/interaction_profiles/ext/eye_gaze_interaction";
inline constexpr const char* kEyeGazePose = "/user/eyes_ext/input/gaze_ext/pose";

// The eye-tracking extensions curvlab enables where the runtime offers them.
struct GazeExtensions {
  bool eye_gaze_interaction = false;  // XR_EXT_eye_gaze_interaction: combined gaze
  bool eye_tracking_social = false;   // XR_FB_eye_tracking_social: per-eye gaze
  [[nodiscard]] std::vector<std::string> names() const;
  [[nodiscard]] bool any() const { return eye_gaze_interaction || eye_tracking_social; }
};
GazeExtensions gaze_extensions_in(const std::vector<std::string>& offered);

// The ray of an OpenXR gaze pose: from its position along its −Z axis.
io::GazeRay gaze_ray(const XrPosef& pose, bool valid, std::optional<double> confidence = std::nullopt);

// The vergence of two eyes' rays (lab frame), read in the head's frame
// with geometry::vergence_of, the perception model's own definition: the
// left eye's yaw toward its ray minus the right eye's, in the plane of the
// eyes' axis and the head's forward direction; positive converging. The
// distance is where symmetric lines with that vergence meet, from the
// midpoint of the eyes: IPD / (2 tan(angle / 2)), none at or beyond parallel.
io::Vergence vergence_of(const StagePose& head, const io::GazeRay& left, const io::GazeRay& right);

// The eye trackers of one session. Made after the instance (the combined
// gaze's action set and its suggested binding must precede the attach),
// started once the session's action sets are attached. Owns the gaze action
// set, its action space and the per-eye tracker; destroy it before the
// session. Move-only; used on the frame thread only.
class EyeTracking {
 public:
  // Combined gaze where the system says it supports it
  // (supportsEyeGazeInteraction); per-eye gaze where the extension is
  // enabled, until start() finds the headset has no eye tracker.
  static harness::Result<EyeTracking> create(const Instance& instance, XrSystemId system, GazeExtensions enabled);
  EyeTracking(EyeTracking&&) noexcept;
  EyeTracking& operator=(EyeTracking&&) noexcept;
  EyeTracking(const EyeTracking&) = delete;
  EyeTracking& operator=(const EyeTracking&) = delete;
  ~EyeTracking();

  // What the headset tracks (per_eye() is final after start()).
  [[nodiscard]] bool combined() const;
  [[nodiscard]] bool per_eye() const;
  [[nodiscard]] bool any() const { return combined() || per_eye(); }
  // The action set to attach with curvlab's and to sync each frame;
  // XR_NULL_HANDLE without combined gaze.
  [[nodiscard]] XrActionSet action_set() const;
  // After xrAttachSessionActionSets: the gaze action space and the per-eye
  // tracker.
  harness::Result<harness::Done> start(XrSession session);
  // The gaze at `time` in `stage`, the head located there at the same time
  // (for the vergence). A failing query is lost tracking (invalid rays),
  // except a lost session or instance, returned as the failing result.
  struct Located {
    io::Gaze gaze;
    XrResult fatal = XR_SUCCESS;  // XR_ERROR_SESSION_LOST & co.; the call in `call`
    const char* call = "";
  };
  Located locate(XrSpace stage, XrTime time, const StagePose& head) const;

 private:
  struct State;
  explicit EyeTracking(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace curvlab::harness::xr
