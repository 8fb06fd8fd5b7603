// Where a session's lab poses come from (DESIGN.md §6): the headset and
// controllers (xr/backend.hpp), the desktop window's keyboard and mouse
// (desktop/desktop.hpp), or a generated or recorded trajectory
// (runner/headless.hpp). Poses are asked for each frame at the time the
// display will show it.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/harness/io/frame.hpp"

namespace curvlab::harness::io {

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
};

}  // namespace curvlab::harness::io
