// Where curvlab's STAGE space lies in the runtime's STAGE (docs/xr.md, "The
// runtime's other events"): the runtime may move STAGE's origin (a redrawn
// play area or boundary), but the room and the table did not move and the
// table's calibration is in the lab frame, so curvlab locates everything in a
// STAGE space offset by the inverse of each move the runtime describes. A pure
// value, like session_state.hpp: the runtime's moves and the frames' display
// times in, which offset to use out; the tracked poses (tracked_poses.hpp)
// make the OpenXR spaces it names. Not thread-safe.
#pragma once

#include <openxr/openxr.h>

#include <cstdint>
#include <optional>

namespace curvlab::harness::xr {

class StageAnchor {
 public:
  // The offset (XrReferenceSpaceCreateInfo::poseInReferenceSpace) of a STAGE
  // space that keeps the lab frame after the runtime moved STAGE's origin to
  // `moved` (the new origin in the previous STAGE, poseInPreviousSpace): with
  // Q the offset of the latest move (the one waiting for its change time,
  // else the one in force), Q' = P⁻¹ · Q. nullopt where the runtime does not
  // say where the new origin lies (poseValid false): the lab frame cannot be
  // kept, the table may now be anywhere in STAGE.
  [[nodiscard]] std::optional<XrPosef> offset_after(bool pose_valid, const XrPosef& moved) const;
  // A space with `offset` was made; it replaces the one in force for the
  // frames displayed at or after `change_time` (XrTime). A later move
  // announced before then replaces it.
  void schedule(const XrPosef& offset, std::int64_t change_time);
  // Whether the frame displayed at `display_time` is the first in the
  // scheduled space (then follow()).
  [[nodiscard]] bool due(std::int64_t display_time) const;
  // The scheduled space is the one in force.
  void follow();
  // The offset in force (identity until the first move is followed).
  [[nodiscard]] const XrPosef& offset() const { return current_; }
  [[nodiscard]] bool pending() const { return pending_.has_value(); }

 private:
  XrPosef current_{{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
  std::optional<XrPosef> pending_;
  std::int64_t change_at_ = 0;
};

}  // namespace curvlab::harness::xr
