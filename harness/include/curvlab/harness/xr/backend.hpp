// The OpenXR backend (DESIGN.md §6): XR_KHR_vulkan_enable2, a STAGE reference
// space, one swapchain per eye, poses located at the predicted display time,
// controllers through action sets, session-state handling. Without a runtime
// the factory returns the OpenXR result by name and what to install.
#pragma once

#include "curvlab/harness/devices/clock.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"

#include <memory>
#include <optional>
#include <string>

namespace curvlab::xr {

struct XrBackendOptions {
  std::string application_name = "curvlab";
  const devices::Clock* clock = nullptr;  // the session's; required
  // Offer copies of the submitted images for the operator window
  // (Display::mirror()); the swapchains can be copied from either way.
  bool mirror = false;
  std::optional<std::uint32_t> msaa;  // samples per pixel requested (clamped); nullopt: the device's automatic count
  // The display refresh rate to ask the headset for (the protocol's
  // [backend] refresh_hz), where the runtime offers XR_FB_display_refresh_rate
  // and that rate; nullopt: the runtime's rate.
  std::optional<double> refresh_hz;
};

// What the controllers of curvlab's action set can press (button names as
// protocols write them); pages continue on a trigger or A.
harness::io::Reach controller_reach();

// No runtime or no headset: an Error of kind `device` naming the OpenXR
// result and what to install; another failing call: `api`. Once running, a
// failing OpenXR or Vulkan call throws DeviceFailure
// ("xrWaitFrame: XR_ERROR_SESSION_LOST").
harness::Result<std::unique_ptr<harness::io::InteractiveDisplay>> make_xr_backend(const XrBackendOptions& options);

}  // namespace curvlab::xr
