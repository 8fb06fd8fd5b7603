// The Vulkan instance and device that the OpenXR runtime makes for curvlab's
// renderer (XR_KHR_vulkan_enable2), and the graphics binding a session is
// created with: the graphics half of the session (hello_xr's graphics
// plugin). Private to harness/src/xr.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/context.hpp"

#include "platform.hpp"

namespace curvlab::harness::xr {

// XR_KHR_vulkan_enable2's functions, for one instance and system.
struct VulkanEnable2 {
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  PFN_xrGetVulkanGraphicsRequirements2KHR requirements = nullptr;
  PFN_xrCreateVulkanInstanceKHR create_instance = nullptr;
  PFN_xrGetVulkanGraphicsDevice2KHR physical_device = nullptr;
  PFN_xrCreateVulkanDeviceKHR create_device = nullptr;
};

harness::Result<VulkanEnable2> load_vulkan_enable2(XrInstance xr, XrSystemId sys);

// Required before the session; curvlab needs Vulkan 1.3 (dynamic rendering).
harness::Result<harness::Done> check_vulkan_version(const VulkanEnable2& fns);

// The renderer's context with its Vulkan instance and device made through
// the runtime, from the renderer's create-infos.
harness::Result<renderer::Context> runtime_made_context(const VulkanEnable2& fns);

// What xrCreateSession is given to draw with `context`.
XrGraphicsBindingVulkan2KHR graphics_binding(const renderer::Context& context);

}  // namespace curvlab::harness::xr
