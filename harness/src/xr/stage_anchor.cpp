#include "curvlab/harness/xr/stage_anchor.hpp"

#include "curvlab/harness/xr/views.hpp"

namespace curvlab::harness::xr {

std::optional<XrPosef> StageAnchor::offset_after(bool pose_valid, const XrPosef& moved) const {
  if (!pose_valid) return std::nullopt;
  // poseInReferenceSpace Q keeps lab coordinates: lab = Q⁻¹ · stage. With
  // the old stage = P · new stage (P the new origin in the old), the new
  // space needs Q' = P⁻¹ · Q.
  const StagePose p = to_stage_pose(moved);
  const StagePose before = to_stage_pose(pending_ ? *pending_ : current_);
  const glm::dquat inv = glm::inverse(glm::normalize(p.orientation));
  StagePose offset;
  offset.orientation = inv * before.orientation;
  offset.position_m = inv * (before.position_m - p.position_m);
  return to_xr_pose(offset);
}

void StageAnchor::schedule(const XrPosef& offset, std::int64_t change_time) {
  pending_ = offset;
  change_at_ = change_time;
}

bool StageAnchor::due(std::int64_t display_time) const { return pending_ && display_time >= change_at_; }

void StageAnchor::follow() {
  if (!pending_) return;
  current_ = *pending_;
  pending_.reset();
}

}  // namespace curvlab::harness::xr
