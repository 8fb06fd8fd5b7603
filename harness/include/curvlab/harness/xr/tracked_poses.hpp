// The headset's tracked poses as a pose source (io/pose_source.hpp): the
// head (the VIEW space), both hands (the controllers' grip poses) and, where
// the headset tracks the eyes, the gaze (gaze.hpp), all located in STAGE at a
// frame's predicted display time. STAGE is curvlab's lab frame; where the
// runtime moves its origin, the lab frame is kept by an offset STAGE space
// (stage_anchor.hpp), or the attempt is dropped (recenter) where it cannot be.
//
// Owns the STAGE and VIEW reference spaces, the grip spaces and the eye
// trackers; destroyed before the session. Borrows the session; used on the
// frame thread only, not thread-safe.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/io/pose_source.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/controllers.hpp"
#include "curvlab/harness/xr/gaze.hpp"
#include "curvlab/harness/xr/handle.hpp"
#include "curvlab/harness/xr/session.hpp"
#include "curvlab/harness/xr/stage_anchor.hpp"
#include "curvlab/harness/xr/views.hpp"

#include <openxr/openxr.h>

#include <array>
#include <memory>
#include <optional>
#include <string>

namespace curvlab::harness::xr {

class TrackedPoses final : public harness::io::PoseSource, private SessionPart {
 public:
  // The eye trackers (their action set suggested before the attach), the
  // STAGE and VIEW spaces, the attach of the controllers' and the eye gaze's
  // action sets (once, together), and a grip space per hand.
  static harness::Result<std::unique_ptr<TrackedPoses>> create(Session& session, const Controllers& controllers);
  ~TrackedPoses() override;

  // --- the frame loop (the swapchain display) ---
  // Switches to the STAGE space that keeps the lab frame once the frame's
  // display time has reached the runtime's change time.
  void follow_stage_change(XrTime display_time);
  // Locates the head, the hands and the gaze at the frame's display time.
  void locate(XrTime display_time);
  // A frame while the runtime has the session stopped: nothing is tracked.
  void lose_tracking();
  // STAGE as curvlab uses it (views and layers are in it too).
  [[nodiscard]] XrSpace stage() const { return stage_.get(); }
  // VIEW: the head (the rig's nose), where head-locked panels are placed.
  [[nodiscard]] XrSpace view() const { return view_.get(); }
  // The head at the last locate (the VIEW space in STAGE).
  [[nodiscard]] const StagePose& head() const { return head_; }

  // --- io::PoseSource ---
  // Located in locate() at this frame's predicted display time.
  geometry::LabFrame poses(const harness::io::FrameTiming& frame) override;
  [[nodiscard]] harness::io::HeadTracking head_tracking() const override;
  [[nodiscard]] std::string describe_head_tracking() const override;
  [[nodiscard]] std::optional<harness::io::Gaze> gaze() const override { return gaze_; }

 private:
  explicit TrackedPoses(Session& session) : session_(session) {}
  harness::Result<harness::Done> make_spaces(const Controllers& controllers);
  void on_event(const XrEventDataBuffer& event) override;
  void on_stage_change(const XrEventDataReferenceSpaceChangePending& e);
  // The space's pose in STAGE at `t` and its flags (0 where it failed).
  std::pair<StagePose, XrSpaceLocationFlags> locate_space(XrSpace space, XrTime t);

  Session& session_;
  SpaceHandle stage_;
  SpaceHandle view_;
  std::array<SpaceHandle, 2> grip_;  // left, right
  // The runtime's STAGE with the offset that keeps the lab frame where it
  // was before the runtime moved STAGE's origin (identity until then); a
  // moved space waits in stage_next_ for its change time.
  StageAnchor anchor_;
  SpaceHandle stage_next_;
  // Destroyed before the spaces and the session it was started on.
  std::optional<EyeTracking> eyes_;

  StagePose head_;
  XrSpaceLocationFlags head_flags_ = 0;  // the head's at the last locate
  geometry::LabFrame lab_;
  std::optional<harness::io::Gaze> gaze_;  // located with lab_; nullopt without eye tracking
};

}  // namespace curvlab::harness::xr
