// Where a frame goes. The renderer draws into one image per eye supplied by a
// target: offscreen images read back to the CPU (headless runs, tests,
// replay), and later a desktop window or OpenXR swapchain images (acquired
// per frame by the target; per-eye pose and asymmetric FOV come with the
// FrameDescription, as OpenXR's views give them).
#pragma once

#include "curvlab/renderer/view.hpp"

#include <vulkan/vulkan_raii.hpp>

namespace curvlab::renderer {

// An image the renderer draws one eye into. The target owns it; the renderer
// only records commands that use it during render().
struct EyeImage {
  vk::Image image;
  vk::ImageView view;
  vk::Extent2D extent;
  vk::Format format = vk::Format::eR8G8B8A8Srgb;
  // The layout the renderer leaves the image in (e.g. TransferSrcOptimal for
  // a read-back, ColorAttachmentOptimal for an OpenXR swapchain image).
  vk::ImageLayout final_layout = vk::ImageLayout::eTransferSrcOptimal;
};

// Implementations: OffscreenTarget (here); window and OpenXR swapchain
// targets plug in through the same four calls. Not thread-safe.
class RenderTarget {
 public:
  virtual ~RenderTarget() = default;
  RenderTarget() = default;
  RenderTarget(const RenderTarget&) = delete;
  RenderTarget& operator=(const RenderTarget&) = delete;

  // The image to draw this eye into for the coming frame (acquired here).
  virtual EyeImage eye_image(Eye eye) = 0;
  // Commands after the eye was drawn (or cleared), in the frame's command
  // buffer: copies for a read-back, nothing for a swapchain.
  virtual void record_after(const vk::raii::CommandBuffer& cb, Eye eye) = 0;
  // Called once the GPU finished the frame (read back, release images).
  virtual void frame_finished() = 0;
  // True when the images keep their content between frames, so a frame
  // identical to the last one need not be drawn again (headless).
  [[nodiscard]] virtual bool preserves_contents() const = 0;
  // Identifies the images, so a re-created target is never taken as unchanged.
  [[nodiscard]] virtual std::uint64_t identity() const = 0;
};

}  // namespace curvlab::renderer
