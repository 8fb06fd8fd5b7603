// The headset as one object (DESIGN.md §6): the OpenXR session
// (xr/session.hpp), the swapchain display (xr/swapchain_display.hpp), the
// tracked poses (xr/tracked_poses.hpp) and the controllers
// (xr/controllers.hpp) behind one InteractiveDisplay, for programs that drive
// the headset without a station (bench/operator_cost.cpp). The CLI composes
// the same parts itself (harness/src/cli/station.cpp). Without a runtime the
// factory returns the OpenXR result by name and what to install.
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/controllers.hpp"

#include <memory>
#include <optional>
#include <string>

namespace curvlab::harness::xr {

struct XrBackendOptions {
  std::string application_name = "curvlab";
  const harness::io::Clock* clock = nullptr;  // the session's; required
  // Offer copies of the submitted images for the operator window
  // (Display::mirror()); the swapchains can be copied from either way.
  bool mirror = false;
  std::optional<std::uint32_t> msaa;  // samples per pixel requested (clamped); nullopt: the device's automatic count
  // The display refresh rate to ask the headset for (the protocol's
  // [backend] refresh_hz), where the runtime offers XR_FB_display_refresh_rate
  // and that rate; nullopt: the runtime's rate.
  std::optional<double> refresh_hz;
};

// No runtime or no headset: an Error of kind `device` naming the OpenXR
// result and what to install; another failing call: `api`. Once running, a
// failing OpenXR or Vulkan call throws DeviceFailure
// ("xrWaitFrame: XR_ERROR_SESSION_LOST").
harness::Result<std::unique_ptr<harness::io::InteractiveDisplay>> make_xr_backend(const XrBackendOptions& options);

}  // namespace curvlab::harness::xr
