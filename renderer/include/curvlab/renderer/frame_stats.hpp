// What a frame did (renderer.hpp), apart from the renderer itself so that
// code which only passes the counts on (the harness's backend interface)
// does not include Vulkan.
#pragma once

#include <cstdint>

namespace curvlab::renderer {

// What a frame did, for logs and for tests of the skipping.
struct FrameStats {
  int views = 0;      // eyes drawn (an eye showing only the background is not a view)
  int passes = 0;     // rendering passes recorded (one per drawn eye; both hemispheres share it)
  int draws = 0;      // draw calls
  int culled = 0;     // draws skipped by culling
  std::uint64_t triangles = 0;
  std::uint64_t lines = 0;
  bool back_hemisphere = false;
  bool reused = false;  // unchanged headless frame: nothing recorded or submitted
  int max_level = 0;    // largest native subdivision level used
  double error_px = 0.0;  // estimated worst geodesic-edge error at that level
  double cpu_ms = 0.0;  // planning and recording
  double gpu_ms = 0.0;  // timestamps around the frame's commands
  double frame_ms = 0.0;  // wall time of render(), submit and wait included
};

}  // namespace curvlab::renderer
