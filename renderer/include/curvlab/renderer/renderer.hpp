// The renderer: turns a Scene and a FrameDescription into per-eye images on a
// RenderTarget, following the render plan (plan.hpp). Meshes are built per
// subdivision level on first use and uploaded once; GPU objects that are
// replaced are retired to the frame slot that last used them and destroyed
// only after that slot's fence has signalled.
#pragma once

#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/frame_stats.hpp"
#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/target.hpp"

#include <map>
#include <memory>
#include <optional>
#include <tuple>

namespace curvlab::renderer {

struct RendererOptions {
  glm::vec4 background = palette::background;  // linear RGBA
  std::size_t frames_in_flight = 2;
  // Samples per pixel (1, 2, 4 or 8); the renderer uses the largest count
  // the device supports that is not above this (Renderer::msaa()).
  // nullopt: the device's automatic count (automatic_msaa).
  std::optional<std::uint32_t> msaa = 4;
};

// The sample count a device can draw with: the largest of 1, 2, 4, 8 not
// above `requested` that both its colour and depth framebuffers support.
std::uint32_t supported_msaa(const Context& ctx, std::uint32_t requested);

// The count "auto" draws with: 4 on a GPU, 1 on a CPU device (lavapipe).
// A GPU multisamples at little cost; a CPU device pays per sample and per
// pixel (4 samples cost lavapipe about 5 times a frame's time), while the
// cue stick's edges do not depend on samples at all (docs/renderer.md,
// "The cue stick's coverage"): only the table's and balls' edges alias.
std::uint32_t automatic_msaa(const Context& ctx);

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

  // The samples per pixel every frame is drawn with (1: no multisampling);
  // each eye is drawn multisampled and resolved into the target's image.
  [[nodiscard]] std::uint32_t msaa() const;
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
