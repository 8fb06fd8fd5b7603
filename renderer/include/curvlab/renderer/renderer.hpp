// The renderer: turns a Scene and a FrameDescription into per-eye images on a
// RenderTarget, following the render plan (plan.hpp). Meshes are built per
// subdivision level on first use and uploaded once; GPU objects that are
// replaced are retired to the frame slot that last used them and destroyed
// only after that slot's fence has signalled.
#pragma once

#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/frame_stats.hpp"
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
  // is not drawn again (stats.reused). A failing Vulkan call (a lost device)
  // throws VulkanFailure; the renderer can then only be destroyed.
  FrameStats render(const Scene& scene, const FrameDescription& frame, RenderTarget& target);

  // The plan of the last frame drawn.
  [[nodiscard]] const RenderPlan& last_plan() const;
  // Waits until the GPU has finished every submitted frame; a failure (a
  // lost device) throws VulkanFailure, as render() does.
  void wait_idle();
  // The same for teardown paths: never throws, ignores a lost device.
  void wait_idle_noexcept() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace curvlab::renderer
