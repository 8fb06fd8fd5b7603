// The renderer: turns a Scene and a FrameDescription into per-eye images on a
// RenderTarget, following the render plan (plan.hpp). Meshes are built per
// subdivision level on first use and uploaded once; GPU objects that are
// replaced are retired to the frame slot that last used them and destroyed
// only after that slot's fence has signalled.
#pragma once

#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/target.hpp"

#include <map>
#include <memory>
#include <tuple>

namespace curvlab::renderer {

struct RendererOptions {
  glm::vec4 background{0.015f, 0.017f, 0.03f, 1.0f};  // the void
  std::size_t frames_in_flight = 2;
};

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

// Owns pipelines, meshes, textures, depth images and frame slots. Holds a
// reference to the Context, which must outlive it. Not thread-safe.
class Renderer {
 public:
  Renderer(const Context& ctx, RendererOptions options = {});
  ~Renderer();
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) = delete;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // Draws the frame and, for targets that preserve contents (headless),
  // waits for it. A frame identical to the previous one on the same target
  // is not drawn again (stats.reused).
  FrameStats render(const Scene& scene, const FrameDescription& frame, RenderTarget& target);

  // The plan of the last frame drawn.
  [[nodiscard]] const RenderPlan& last_plan() const;
  // Waits until the GPU has finished every submitted frame.
  void wait_idle();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::renderer
