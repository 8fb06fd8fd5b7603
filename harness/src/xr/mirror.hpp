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
//
// Owns its command pool, fence and staging buffer; borrows the Vulkan
// context, which must outlive it.
#pragma once

#include "curvlab/harness/io/display.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/gpu.hpp"

#include <array>
#include <atomic>
#include <cstdint>

namespace curvlab::harness::xr {

class OperatorMirror final : public harness::io::FrameMirror {
 public:
  // `eye`: each eye's image size; `bgra`: the swapchain's byte order;
  // `linear`: a UNORM swapchain.
  OperatorMirror(const renderer::Context& ctx, vk::Extent2D eye, bool bgra, bool linear);
  ~OperatorMirror() override;

  void request() override;
  bool take(harness::io::MirrorImage& out) override;

  // Frame thread, with both eyes' swapchain images still acquired and the
  // frame's own commands submitted: copies them when a copy was requested.
  void copy(const std::array<vk::Image, 2>& images);

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
  std::atomic<int> state_{kIdle};
};

}  // namespace curvlab::harness::xr
