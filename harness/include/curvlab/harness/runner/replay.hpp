// `curvlab replay`: re-renders what a participant saw in one frame of a
// stored trial, from the logged poses — the head's virtual pose of that
// frame (tracking_samples.virtual_pose) and the stimulus placement logged at
// onset — with the trial's stored settings (the protocol re-expanded for the
// session's participant, the staircase's intensity where there was one).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
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

struct ReplayError {
  bool usage = false;
  std::string message;
};

std::variant<ReplayResult, ReplayError> replay_frame(const ReplayRequest& request);

}  // namespace curvlab::harness::runner
