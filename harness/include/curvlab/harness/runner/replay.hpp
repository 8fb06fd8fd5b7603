// `curvlab replay`: re-renders what a participant saw in one frame of a
// stored trial, from what was recorded — the head's virtual pose of that
// frame (tracking_samples.virtual_pose), the stimulus placement logged at
// onset, the eye geometry the frame was drawn with (frames.eye_views: eye
// offsets, asymmetric fields of view, image size), and the trial's settings
// (the protocol re-expanded for the session's participant, the staircase's
// intensity, an adjustment's value at that frame). Everything is read
// through data/session_reader.hpp.
#pragma once

#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::runner {

struct ReplayRequest {
  std::string db_path;
  std::int64_t session_id = 0;
  std::int64_t trial_index = 0;          // 0-based, as trials.trial_index
  std::optional<std::int64_t> frame_index;  // default: the onset frame
  std::string out_dir;
  bool software = false;
};

struct ReplayResult {
  std::vector<std::string> files;  // left.png, right.png, replay.json
  std::int64_t frame_index = 0;
  std::string phase;  // fixation, stimulus, response or iti at that frame
  std::string device;
};

// Errors: not_found (no database, session, trial, onset or head pose at the
// frame; exit 2), usage (a trial index out of range), corrupt (a stored pose
// or eye geometry of the wrong size), device (no Vulkan device), io.
Result<ReplayResult> replay_frame(const ReplayRequest& request);

}  // namespace curvlab::harness::runner
