// The order follows XR_KHR_vulkan_enable2: graphics requirements, then the
// Vulkan instance, physical device and device, each made by the runtime from
// the renderer's create-info (the renderer's ContextEmbedding hooks).
#include "runtime_vulkan.hpp"

#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/xr/instance.hpp"

#include <iostream>
#include <string>
#include <utility>
#include <variant>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;

namespace {

std::string vk_result(VkResult r) { return vk::to_string(static_cast<vk::Result>(r)); }

// A failing runtime call in a hook: no Vulkan device through this runtime.
renderer::RenderError runtime_failure(std::string message) {
  return {renderer::RenderError::Kind::device, std::move(message)};
}

// The loader's entry point the runtime makes Vulkan objects through. On
// Windows vulkan-1.dll is loaded at run time (no import library).
PFN_vkGetInstanceProcAddr vulkan_entry_point() {
#ifdef _WIN32
  static const vk::DynamicLoader loader;
  return loader.getProcAddress<PFN_vkGetInstanceProcAddr>("vkGetInstanceProcAddr");
#else
  return &vkGetInstanceProcAddr;
#endif
}

decltype(renderer::ContextHooks::create_instance) instance_hook(const VulkanEnable2& fns) {
  return [fns](const VkInstanceCreateInfo& info) -> std::variant<VkInstance, renderer::RenderError> {
    auto ci = tagged<XrVulkanInstanceCreateInfoKHR>(XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR);
    ci.systemId = fns.system;
    ci.pfnGetInstanceProcAddr = vulkan_entry_point();
    ci.vulkanCreateInfo = &info;
    VkInstance instance = VK_NULL_HANDLE;
    VkResult vr = VK_SUCCESS;
    if (const XrResult r = fns.create_instance(fns.instance, &ci, &instance, &vr); XR_FAILED(r))
      return runtime_failure(failure_of(r, "xrCreateVulkanInstanceKHR").message);
    if (vr != VK_SUCCESS)
      return runtime_failure("xrCreateVulkanInstanceKHR: vkCreateInstance returned " + vk_result(vr));
    return instance;
  };
}

decltype(renderer::ContextHooks::pick_physical_device) physical_device_hook(const VulkanEnable2& fns) {
  return [fns](VkInstance instance) -> std::variant<VkPhysicalDevice, renderer::RenderError> {
    auto gi = tagged<XrVulkanGraphicsDeviceGetInfoKHR>(XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR);
    gi.systemId = fns.system;
    gi.vulkanInstance = instance;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    if (const XrResult r = fns.physical_device(fns.instance, &gi, &physical); XR_FAILED(r))
      return runtime_failure(failure_of(r, "xrGetVulkanGraphicsDevice2KHR").message);
    return physical;
  };
}

decltype(renderer::ContextHooks::create_device) device_hook(const VulkanEnable2& fns) {
  return [fns](VkPhysicalDevice physical, const VkDeviceCreateInfo& info)
             -> std::variant<VkDevice, renderer::RenderError> {
    auto ci = tagged<XrVulkanDeviceCreateInfoKHR>(XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR);
    ci.systemId = fns.system;
    ci.pfnGetInstanceProcAddr = vulkan_entry_point();
    ci.vulkanPhysicalDevice = physical;
    ci.vulkanCreateInfo = &info;
    VkDevice device = VK_NULL_HANDLE;
    VkResult vr = VK_SUCCESS;
    if (const XrResult r = fns.create_device(fns.instance, &ci, &device, &vr); XR_FAILED(r))
      return runtime_failure(failure_of(r, "xrCreateVulkanDeviceKHR").message);
    if (vr != VK_SUCCESS)
      return runtime_failure("xrCreateVulkanDeviceKHR: vkCreateDevice returned " + vk_result(vr));
    return device;
  };
}

}  // namespace

Result<VulkanEnable2> load_vulkan_enable2(XrInstance xr, XrSystemId sys) {
  VulkanEnable2 fns{.instance = xr, .system = sys};
  for (auto [name, r] : {std::pair{"xrGetVulkanGraphicsRequirements2KHR",
                                   load(xr, "xrGetVulkanGraphicsRequirements2KHR", fns.requirements)},
                         std::pair{"xrCreateVulkanInstanceKHR",
                                   load(xr, "xrCreateVulkanInstanceKHR", fns.create_instance)},
                         std::pair{"xrGetVulkanGraphicsDevice2KHR",
                                   load(xr, "xrGetVulkanGraphicsDevice2KHR", fns.physical_device)},
                         std::pair{"xrCreateVulkanDeviceKHR",
                                   load(xr, "xrCreateVulkanDeviceKHR", fns.create_device)}})
    if (XR_FAILED(r)) return failure_of(r, name);
  return fns;
}

Result<Done> check_vulkan_version(const VulkanEnable2& fns) {
  auto req = tagged<XrGraphicsRequirementsVulkan2KHR>(XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR);
  if (const XrResult r = fns.requirements(fns.instance, fns.system, &req); XR_FAILED(r))
    return failure_of(r, "xrGetVulkanGraphicsRequirements2KHR");
  const XrVersion needed = XR_MAKE_VERSION(1, 3, 0);
  if (req.minApiVersionSupported > needed)
    return Error{Error::Kind::device, "the OpenXR runtime needs a newer Vulkan than 1.3, which curvlab uses; "
                                      "update curvlab or use another runtime"};
  if (XR_VERSION_MAJOR(req.maxApiVersionSupported) == 1 &&
      XR_VERSION_MINOR(req.maxApiVersionSupported) < 3)
    std::cerr << "curvlab: xr: the runtime was tested with Vulkan up to "
              << XR_VERSION_MAJOR(req.maxApiVersionSupported) << "."
              << XR_VERSION_MINOR(req.maxApiVersionSupported)
              << "; curvlab uses 1.3 and tries anyway\n";
  return Done{};
}

Result<renderer::Context> runtime_made_context(const VulkanEnable2& fns) {
  renderer::ContextEmbedding runtime_made;
  runtime_made.hooks.create_instance = instance_hook(fns);
  runtime_made.hooks.pick_physical_device = physical_device_hook(fns);
  runtime_made.hooks.create_device = device_hook(fns);
  return harness::from_renderer(renderer::Context::create(renderer::ContextOptions{}, std::move(runtime_made)),
                                "cannot render for the headset: ");
}

XrGraphicsBindingVulkan2KHR graphics_binding(const renderer::Context& c) {
  auto binding = tagged<XrGraphicsBindingVulkan2KHR>(XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR);
  binding.instance = static_cast<VkInstance>(*c.instance());
  binding.physicalDevice = static_cast<VkPhysicalDevice>(*c.physical());
  binding.device = static_cast<VkDevice>(*c.device());
  binding.queueFamilyIndex = c.queue_family();
  binding.queueIndex = 0;
  return binding;
}

}  // namespace curvlab::harness::xr
