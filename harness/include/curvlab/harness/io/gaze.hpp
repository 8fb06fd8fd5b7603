// Where the participant looks (DESIGN.md §6, "Eye gaze is logged where the
// runtime offers it"): gaze rays located at a frame's predicted display time
// in the lab frame (STAGE: metres, y up, −z forward), as a headset with eye
// tracking reports them (xr/gaze.hpp). Lost tracking is data: a ray that is
// not valid stays in the record with `valid` false.
#pragma once

#include "curvlab/geometry/space.hpp"

#include <array>
#include <optional>

namespace curvlab::harness::io {

struct GazeRay {
  bool valid = false;
  std::optional<double> confidence;  // 0–1 where the eye tracker reports one
  geometry::Vec3 origin_m{0.0};
  geometry::Vec3 direction{0.0, 0.0, -1.0};  // unit
};

// The vergence of the two eyes' rays: the left eye's yaw toward its ray minus
// the right eye's, in the plane of the eyes' axis and the head's forward
// direction (geometry::vergence_of, the perception model's vergence demand):
// positive converging, 0 parallel, negative diverging beyond parallel.
struct Vergence {
  double angle_rad = 0.0;
  // The distance from the midpoint between the eyes at which lines with
  // this vergence meet (IPD / (2 tan(angle / 2))); nullopt where they do not
  // (parallel or diverging).
  std::optional<double> distance_m;
};

struct Gaze {
  std::optional<GazeRay> combined;            // one ray for both eyes (XR_EXT_eye_gaze_interaction)
  std::optional<std::array<GazeRay, 2>> eyes;  // left, right (XR_FB_eye_tracking_social)
  std::optional<Vergence> vergence;           // with both eyes valid
};

}  // namespace curvlab::harness::io
