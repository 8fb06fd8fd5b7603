#include "curvlab/renderer/vulkan_failure.hpp"

#include <vulkan/vulkan_core.h>

#include <array>
#include <cctype>
#include <utility>

namespace curvlab::renderer {

std::string vk_result_name(std::int32_t result) {
  switch (static_cast<VkResult>(result)) {
#define CURVLAB_VK_RESULT(name) \
  case name:                    \
    return #name;
    CURVLAB_VK_RESULT(VK_SUCCESS)
    CURVLAB_VK_RESULT(VK_NOT_READY)
    CURVLAB_VK_RESULT(VK_TIMEOUT)
    CURVLAB_VK_RESULT(VK_EVENT_SET)
    CURVLAB_VK_RESULT(VK_EVENT_RESET)
    CURVLAB_VK_RESULT(VK_INCOMPLETE)
    CURVLAB_VK_RESULT(VK_ERROR_OUT_OF_HOST_MEMORY)
    CURVLAB_VK_RESULT(VK_ERROR_OUT_OF_DEVICE_MEMORY)
    CURVLAB_VK_RESULT(VK_ERROR_INITIALIZATION_FAILED)
    CURVLAB_VK_RESULT(VK_ERROR_DEVICE_LOST)
    CURVLAB_VK_RESULT(VK_ERROR_MEMORY_MAP_FAILED)
    CURVLAB_VK_RESULT(VK_ERROR_LAYER_NOT_PRESENT)
    CURVLAB_VK_RESULT(VK_ERROR_EXTENSION_NOT_PRESENT)
    CURVLAB_VK_RESULT(VK_ERROR_FEATURE_NOT_PRESENT)
    CURVLAB_VK_RESULT(VK_ERROR_INCOMPATIBLE_DRIVER)
    CURVLAB_VK_RESULT(VK_ERROR_TOO_MANY_OBJECTS)
    CURVLAB_VK_RESULT(VK_ERROR_FORMAT_NOT_SUPPORTED)
    CURVLAB_VK_RESULT(VK_ERROR_FRAGMENTED_POOL)
    CURVLAB_VK_RESULT(VK_ERROR_UNKNOWN)
    CURVLAB_VK_RESULT(VK_ERROR_OUT_OF_POOL_MEMORY)
    CURVLAB_VK_RESULT(VK_ERROR_INVALID_EXTERNAL_HANDLE)
    CURVLAB_VK_RESULT(VK_ERROR_FRAGMENTATION)
    CURVLAB_VK_RESULT(VK_ERROR_INVALID_OPAQUE_CAPTURE_ADDRESS)
    CURVLAB_VK_RESULT(VK_PIPELINE_COMPILE_REQUIRED)
    CURVLAB_VK_RESULT(VK_ERROR_SURFACE_LOST_KHR)
    CURVLAB_VK_RESULT(VK_ERROR_NATIVE_WINDOW_IN_USE_KHR)
    CURVLAB_VK_RESULT(VK_SUBOPTIMAL_KHR)
    CURVLAB_VK_RESULT(VK_ERROR_OUT_OF_DATE_KHR)
    CURVLAB_VK_RESULT(VK_ERROR_VALIDATION_FAILED_EXT)
#undef CURVLAB_VK_RESULT
    default:
      return "VkResult " + std::to_string(result);
  }
}

std::string vk_call_name(const std::string& hpp_message) {
  // Vulkan-Hpp names a failing method "vk::Class::method" and a failing
  // RAII constructor by its C function; the message follows after ": ".
  const std::string call = hpp_message.substr(0, hpp_message.find(": "));
  if (call.rfind("vk::", 0) != 0) return call;
  const std::size_t sep = call.rfind("::");
  std::string cls = call.substr(0, sep);
  cls = cls.substr(cls.rfind("::") == std::string::npos ? 0 : cls.rfind("::") + 2);
  std::string method = call.substr(sep + 2);
  static constexpr std::array<std::pair<const char*, const char*>, 4> irregular{
      {{"CommandBuffer::begin", "vkBeginCommandBuffer"},
       {"CommandBuffer::end", "vkEndCommandBuffer"},
       {"CommandBuffer::reset", "vkResetCommandBuffer"},
       {"SwapchainKHR::acquireNextImage", "vkAcquireNextImageKHR"}}};
  for (const auto& [from, to] : irregular)
    if (cls + "::" + method == from) return to;
  if (method.empty()) return call;
  method[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(method[0])));
  // Device-level verbs name the object in the C API (vkCreateBuffer,
  // vkWaitForFences); queue and command-buffer calls prefix the class
  // (vkQueueSubmit, vkDeviceWaitIdle).
  for (const char* verb : {"Create", "Allocate", "Bind", "Map", "Reset", "WaitFor", "Get",
                           "Enumerate", "Update", "Flush", "Invalidate", "Acquire"})
    if (method.rfind(verb, 0) == 0) return "vk" + method;
  return "vk" + cls + method;
}

}  // namespace curvlab::renderer
