// The operator window's copies of the images the swapchain display submits
// (FrameMirror in io/display.hpp). Private to harness/src/xr.
//
// The frame thread records, in a command buffer of its own submitted right
// after the frame's (same queue, so after it), a copy of both eyes into a
// host-visible buffer; the operator's thread waits on the fence and reads
// the buffer. One copy in flight; `state_` hands the buffer and fence between
// the two threads (acquire/release): idle → requested (operator) → copying
// (frame thread) → idle (operator, after reading). A UNORM swapchain holds
// linear values (the compositor encodes them for the display): the copy is
// sRGB-encoded on reading, so the window shows what the headset does.
// The head-locked panels, which the runtime's compositor lays over the eye
// images as quad layers (quad_panels.hpp), are laid over the copy the same
// way on the operator's thread, so the window shows what the participant
// reads.
//
// Owns its command pool, fence and staging buffer; borrows the Vulkan
// context, which must outlive it.
#pragma once

#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/xr/views.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/text.hpp"

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <vector>

namespace curvlab::renderer {
class Scene;
}

namespace curvlab::harness::xr {

// An eye as the copy was rendered for it: its pose in the head's frame
// (VIEW) and its field of view.
struct MirrorEye {
  StagePose in_head;
  FrustumTangents view;
};

// A head-locked panel as a quad layer shows it: its texels' coverage, its
// pose in VIEW (the card in its x–y plane, facing +z) and its size.
struct MirrorPanel {
  renderer::CoverageBitmap text;
  glm::dmat4 in_head{1.0};
  glm::dvec2 size_m{0.0};
};

// Lays `panel` over one eye's sRGB RGBA pixels (`eye_x0`: the eye's first
// column in an image `stride_px` wide), as a compositor does a quad layer:
// each pixel's ray from the eye meets the card's plane, and the panel's
// texel there (nearest) is drawn. Only the card's projected box is visited.
void lay_panel(std::vector<std::uint8_t>& rgba, std::uint32_t stride_px, std::uint32_t eye_x0,
               vk::Extent2D eye_px, const MirrorEye& eye, const MirrorPanel& panel);

class OperatorMirror final : public harness::io::FrameMirror {
 public:
  // `eye`: each eye's image size; `bgra`: the swapchain's byte order;
  // `linear`: a UNORM swapchain.
  OperatorMirror(const renderer::Context& ctx, vk::Extent2D eye, bool bgra, bool linear);
  ~OperatorMirror() override;

  void request() override;
  bool take(harness::io::MirrorImage& out) override;

  // Frame thread: the window has asked for a copy that copy() would make.
  [[nodiscard]] bool wanted() const { return state_.load(std::memory_order_acquire) == kRequested; }
  // Frame thread, with both eyes' swapchain images still acquired and the
  // frame's own commands submitted: copies them when a copy was requested,
  // with the scene's visible head-locked panels when `panels_as_layers`
  // (they are not in the images then) and the eyes they are seen from.
  void copy(const std::array<vk::Image, 2>& images, const renderer::Scene& scene, bool panels_as_layers,
            const std::array<MirrorEye, 2>& eyes);

 private:
  static constexpr int kIdle = 0, kRequested = 1, kCopying = 2;
  const renderer::Context& ctx_;
  vk::Extent2D eye_;
  bool bgra_;
  std::array<std::uint8_t, 256> encode_;
  vk::raii::CommandPool pool_;
  vk::raii::CommandBuffer cb_{nullptr};
  vk::raii::Fence fence_;
  renderer::Buffer staging_;
  // Handed over with the buffer (state_): the panels to lay over the copy.
  std::vector<MirrorPanel> panels_;
  std::array<MirrorEye, 2> eyes_{};
  std::atomic<int> state_{kIdle};
};

}  // namespace curvlab::harness::xr
