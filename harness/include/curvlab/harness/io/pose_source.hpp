// Where a session's lab poses come from (DESIGN.md §6): the headset and
// controllers (xr/backend.hpp), the desktop window's keyboard and mouse
// (desktop/desktop.hpp), or a generated or recorded trajectory
// (runner/headless.hpp). Poses are asked for each frame at the time the
// display will show it.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/io/frame.hpp"
#include "curvlab/harness/io/gaze.hpp"

#include <optional>
#include <string>

namespace curvlab::harness::io {

// How the source tracked the head in the last poses() beyond the pose's own
// `valid` (usable): whether orientation and position are tracked or only
// inferred, for the protocol's [tracking] head_requires. Read every frame.
struct HeadTracking {
  bool orientation_tracked = true;
  bool position_tracked = true;
};

class PoseSource {
 public:
  virtual ~PoseSource() = default;
  PoseSource() = default;
  PoseSource(const PoseSource&) = delete;
  PoseSource& operator=(const PoseSource&) = delete;
  // Lab poses of head and hands for the frame's predicted display time; a
  // device that is not tracked is marked so in its pose. May throw
  // DeviceFailure.
  virtual geometry::LabFrame poses(const FrameTiming& frame) = 0;
  // The head's tracking at the last poses(); sources that know only
  // `valid` report it tracked whenever it is valid.
  [[nodiscard]] virtual HeadTracking head_tracking() const { return {}; }
  // The same in the source's own words (OpenXR: the XrSpaceLocationFlags
  // set), for the message that stops a session waiting for the head; empty:
  // nothing beyond `valid` to report. Formatted only when asked.
  [[nodiscard]] virtual std::string describe_head_tracking() const { return {}; }
  // The participant's gaze located with the last poses() (the same
  // predicted display time); nullopt: the source tracks no eyes.
  [[nodiscard]] virtual std::optional<Gaze> gaze() const { return std::nullopt; }
};

}  // namespace curvlab::harness::io
