// One OpenXR swapchain per eye at the runtime's recommended size, in the
// format curvlab prefers among those offered (stereo.hpp), and the
// acquire → wait → release cycle of a frame's two images. Private to
// harness/src/xr; the swapchain display (swapchain_display.hpp) owns it.
//
// Owns the swapchains (destroyed before the session). Used on the frame
// thread only; not thread-safe.
#pragma once

#include "platform.hpp"

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/handle.hpp"
#include "curvlab/harness/xr/session.hpp"

#include <vulkan/vulkan.hpp>

#include <array>
#include <cstdint>
#include <vector>

namespace curvlab::harness::xr {

// xrWaitSwapchainImage in bounded steps (a runtime's back-pressure): a
// compositor that holds an image is said once (`said`) and, past a limit,
// a failure (Session::fail).
void wait_swapchain_image(Session& session, XrSwapchain swapchain, bool& said);

// A single-sample, single-layer 2D swapchain of `format` and its Vulkan
// images (xrCreateSwapchain, xrEnumerateSwapchainImages).
struct MadeSwapchain {
  SwapchainHandle handle;
  std::vector<XrSwapchainImageVulkan2KHR> images;
};
harness::Result<MadeSwapchain> make_swapchain(const Session& session, std::int64_t format, std::uint32_t width,
                                              std::uint32_t height, XrSwapchainUsageFlags usage);

class EyeSwapchains {
 public:
  static harness::Result<EyeSwapchains> create(const Session& session);

  // The VkFormat the swapchains were made with.
  [[nodiscard]] std::int64_t format() const { return format_; }
  // Each eye's image size (both are the same in every headset curvlab knows;
  // the left eye's is the display's).
  [[nodiscard]] std::uint32_t width(std::size_t eye = 0) const { return eyes_[eye].width; }
  [[nodiscard]] std::uint32_t height(std::size_t eye = 0) const { return eyes_[eye].height; }
  // Where a projection layer's view finds the eye's image.
  [[nodiscard]] XrSwapchainSubImage sub_image(std::size_t eye) const;

  // Acquires both eyes' next images and waits until the compositor lets go
  // of them. A failure releases what must be released and throws
  // DeviceFailure (Session::fail); the frame is lost.
  std::array<vk::Image, 2> acquire(Session& session);
  // Releases the images acquire() handed out (after the frame's commands
  // were submitted, as xrReleaseSwapchainImage requires).
  void release();

 private:
  struct Eye {
    SwapchainHandle handle;
    std::vector<XrSwapchainImageVulkan2KHR> images;
    std::uint32_t width = 0;
    std::uint32_t height = 0;
  };
  EyeSwapchains() = default;
  harness::Result<harness::Done> make(const Session& session, Eye& eye, const XrViewConfigurationView& view) const;

  std::array<Eye, 2> eyes_;
  std::int64_t format_ = 0;
  std::array<bool, 2> acquired_{false, false};
  bool wait_said_ = false;
};

}  // namespace curvlab::harness::xr
