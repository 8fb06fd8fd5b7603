// A session's devices as one value (DESIGN.md §6): one display, one pose
// source and any number of response sources, composed by the CLI's one
// wiring point (harness/src/cli/run.cpp) as a lab sets them up, e.g. the
// headset's display and poses with its controllers and a HID button box.
// The station borrows them; whoever made them owns them and keeps them alive
// for the session.
#pragma once

#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/io/pose_source.hpp"
#include "curvlab/harness/io/response_source.hpp"

#include <vector>

namespace curvlab::harness::io {

// A display that is also where poses and responses come from: the headset
// (its views, tracked head and controllers; xr/backend.hpp) and the desktop
// pilot window (its keyboard and mouse move the head and answer;
// desktop/desktop.hpp).
class InteractiveDisplay : public Display, public PoseSource, public ResponseSource {};

struct Station {
  Display* display = nullptr;
  PoseSource* poses = nullptr;
  std::vector<ResponseSource*> responses;
};

}  // namespace curvlab::harness::io
