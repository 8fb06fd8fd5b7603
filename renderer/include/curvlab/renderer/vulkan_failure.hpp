// A Vulkan call that failed while frames run (a lost device, memory running
// out): the renderer's one run-time exception. Its message names the call as
// the C API spells it and the result by name ("vkQueueSubmit:
// VK_ERROR_DEVICE_LOST"), so the backends can hand it on unchanged. Failures
// while starting (no device, no loader) stay values (context.hpp,
// RenderError). Light on purpose: no Vulkan header, so code that only
// catches it does not pay for vulkan.hpp.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace curvlab::renderer {

// "VK_ERROR_DEVICE_LOST" for VK_ERROR_DEVICE_LOST; unknown codes read
// "VkResult <n>".
std::string vk_result_name(std::int32_t result);

struct VulkanFailure : std::runtime_error {
  VulkanFailure(std::string call_name, std::int32_t vk_result)
      : std::runtime_error(call_name + ": " + vk_result_name(vk_result)),
        call(std::move(call_name)),
        result(vk_result) {}

  std::string call;    // "vkQueueSubmit"
  std::int32_t result;  // the VkResult
};

// The C name of the call a Vulkan-Hpp exception names ("vk::Queue::submit"
// → "vkQueueSubmit"; "vk::raii::Device::createBuffer" → "vkCreateBuffer").
std::string vk_call_name(const std::string& hpp_message);

}  // namespace curvlab::renderer
