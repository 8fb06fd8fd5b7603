// The scene's head-locked panels (instructions, prompts, answers,
// questionnaire items) as OpenXR quad layers in VIEW space, drawn by the
// runtime's compositor over the projection layer: sampled once, straight
// from the panel's own texels to the display, instead of being drawn into
// the eye images and resampled by the compositor's lens warp (docs/xr.md,
// "Panels as quad layers"). Private to harness/src/xr; the swapchain display
// owns it.
//
// One swapchain per panel slot (the k-th visible head-locked panel of the
// scene), grown when a panel's text needs more texels. A panel's texels are
// written into a freshly acquired image only when its text changed (the
// scene's mesh revision); otherwise the layer names the swapchain's last
// released image, as OpenXR lets it. Owns the swapchains and the staging
// buffers; borrows the Vulkan context. Frame thread only; not thread-safe.
#pragma once

#include "platform.hpp"

#include "curvlab/harness/xr/handle.hpp"
#include "curvlab/harness/xr/session.hpp"
#include "curvlab/renderer/gpu.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace curvlab::renderer {
class Context;
class Scene;
}  // namespace curvlab::renderer

namespace curvlab::harness::xr {

// Each coverage value's bytes in a swapchain format (8-bit RGBA or BGRA,
// sRGB or UNORM): the panels' paper and ink (renderer::palette) mixed in
// linear light, as the renderer's text shader mixes them.
std::array<std::array<std::uint8_t, 4>, 256> panel_texels(std::int64_t format);

class QuadPanels {
 public:
  // `format`: the eye swapchains' VkFormat (an 8-bit RGBA or BGRA format,
  // sRGB or UNORM).
  QuadPanels(const renderer::Context& ctx, std::int64_t format);

  // Writes the texels of the scene's visible head-locked panels whose text
  // changed and sets the quad layers for them, in VIEW space `view`. False
  // when a panel's swapchain could not be made (the runtime refused it):
  // the caller then draws the panels into the eye images instead. A failed
  // acquire, wait or copy is a failure of the session (Session::fail).
  bool update(Session& session, XrSpace view, const renderer::Scene& scene);

  // The quad layers of the last update, to follow the projection layer.
  [[nodiscard]] const std::vector<XrCompositionLayerQuad>& layers() const { return layers_; }

 private:
  struct Slot {
    SwapchainHandle handle;
    std::vector<XrSwapchainImageVulkan2KHR> images;
    std::uint32_t width = 0, height = 0;  // the swapchain's size
    renderer::Buffer staging;
    std::uint64_t revision = 0;  // the scene's mesh revision last written (0: none)
  };
  // A swapchain of at least width × height texels in slot `slot`.
  bool fit(Session& session, Slot& slot, std::uint32_t width, std::uint32_t height);
  // The panel's coverage as the swapchain format's bytes, copied into a
  // freshly acquired image.
  void write(Session& session, Slot& slot, const std::vector<std::uint8_t>& coverage, std::uint32_t width,
             std::uint32_t height);

  const renderer::Context& ctx_;
  std::int64_t format_;
  std::array<std::array<std::uint8_t, 4>, 256> texels_;  // coverage → the format's bytes
  std::vector<Slot> slots_;
  std::vector<XrCompositionLayerQuad> layers_;
  bool wait_said_ = false;
};

}  // namespace curvlab::harness::xr
