// The Vulkan instance and device, through the system loader: a GPU when one
// is present, lavapipe (a CPU device) otherwise or on request. With
// validation on, every message of the Khronos validation layer is recorded so
// tests can fail on any of them.
#pragma once

#include "curvlab/renderer/error.hpp"
#include "curvlab/renderer/vulkan_failure.hpp"

#include <vulkan/vulkan_raii.hpp>

#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::renderer {

enum class DeviceChoice {
  automatic,  // the first discrete or integrated GPU, else a CPU device
  software,   // a CPU device (lavapipe) even when a GPU is present
};

// For an embedder that must create the Vulkan objects itself. OpenXR's
// XR_KHR_vulkan_enable2 is the case in point: the runtime creates the
// instance (xrCreateVulkanInstanceKHR), names the physical device
// (xrGetVulkanGraphicsDevice2KHR) and creates the device
// (xrCreateVulkanDeviceKHR) from create-infos the application prepares. Each
// hook gets the create-info the context would have used itself and returns
// the handle, or a RenderError (kind `device`, a message for a person naming
// the call that failed) that Context::create returns as it is. Handles
// returned are owned by the context from then on (destroyed with
// vkDestroyInstance / vkDestroyDevice, as XR_KHR_vulkan_enable2 requires of
// the application). Empty hooks: the context creates and picks as usual.
struct ContextHooks {
  std::function<std::variant<VkInstance, RenderError>(const VkInstanceCreateInfo& info)>
      create_instance;
  std::function<std::variant<VkPhysicalDevice, RenderError>(VkInstance instance)>
      pick_physical_device;
  std::function<std::variant<VkDevice, RenderError>(VkPhysicalDevice physical,
                                                    const VkDeviceCreateInfo& info)>
      create_device;
};

struct ContextOptions {
  DeviceChoice device = DeviceChoice::automatic;
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation
};

// What an embedder adds to a context (a window, an OpenXR runtime). Kept
// apart from ContextOptions so that callers who designate only its fields
// stay warning-free.
struct ContextEmbedding {
  // Extensions the embedder needs besides the context's own (e.g. the
  // window system's surface extensions, from glfwGetRequiredInstanceExtensions).
  // A device lacking one of the device extensions is not chosen.
  std::vector<std::string> instance_extensions;
  std::vector<std::string> device_extensions;
  // Called once the instance exists to make the surface a window presents
  // to (e.g. glfwCreateWindowSurface). The context owns the surface, adds
  // VK_KHR_swapchain to the device and picks a queue family that can present
  // to it; a RenderError (kind `surface`) is returned by Context::create as
  // it is. Empty: no surface (headless, OpenXR).
  std::function<std::variant<VkSurfaceKHR, RenderError>(VkInstance instance)> create_surface;
  ContextHooks hooks;
};


// Messages from the validation layer. Thread-safe: the layer may call from
// any thread that uses the device.
class ValidationLog {
 public:
  void add(std::string message);
  [[nodiscard]] std::size_t count() const;
  [[nodiscard]] std::vector<std::string> messages() const;

 private:
  mutable std::mutex mutex_;
  std::vector<std::string> messages_;
};

// Owns the instance, the debug messenger, the surface (when asked for one),
// the device, one graphics+compute queue (that can also present to the
// surface) and a command pool. Move-only; handles are destroyed in reverse order
// of creation by the vk::raii members. Not thread-safe: one thread records and
// submits (the command pool is not shared).
class Context {
 public:
  static std::variant<Context, RenderError> create(const ContextOptions& options);
  static std::variant<Context, RenderError> create(const ContextOptions& options,
                                                   const ContextEmbedding& embedding);

  Context(Context&&) noexcept = default;
  Context& operator=(Context&&) noexcept = default;
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
  ~Context();

  [[nodiscard]] const vk::raii::Instance& instance() const { return instance_; }
  // The window surface of ContextEmbedding::create_surface (null without one).
  [[nodiscard]] const vk::raii::SurfaceKHR& surface() const { return surface_; }
  [[nodiscard]] const vk::raii::Device& device() const { return device_; }
  [[nodiscard]] const vk::raii::PhysicalDevice& physical() const { return physical_; }
  [[nodiscard]] const vk::raii::Queue& queue() const { return queue_; }
  [[nodiscard]] std::uint32_t queue_family() const { return queue_family_; }
  [[nodiscard]] const vk::raii::CommandPool& command_pool() const { return command_pool_; }
  [[nodiscard]] const std::string& device_name() const { return device_name_; }
  [[nodiscard]] const std::string& driver_info() const { return driver_info_; }
  [[nodiscard]] bool is_software() const { return software_; }
  [[nodiscard]] double timestamp_period_ns() const { return timestamp_period_ns_; }
  [[nodiscard]] bool validation_enabled() const { return validation_; }
  // Messages recorded so far (always empty without validation).
  [[nodiscard]] const ValidationLog& validation_log() const { return *log_; }

  // Index of a memory type with the given bits and properties; a broken
  // contract (no such type) aborts.
  [[nodiscard]] std::uint32_t memory_type(std::uint32_t type_bits,
                                          vk::MemoryPropertyFlags props) const;

  // Records with `record` into a one-time command buffer, submits and waits.
  // Throws VulkanFailure when a call fails (a lost device).
  template <class F>
  void submit_and_wait(F&& record) const {
    try {
      vk::raii::CommandBuffers cbs(device_, {.commandPool = *command_pool_,
                                             .level = vk::CommandBufferLevel::ePrimary,
                                             .commandBufferCount = 1});
      const vk::raii::CommandBuffer& cb = cbs.front();
      cb.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
      record(cb);
      cb.end();
      vk::raii::Fence fence(device_, vk::FenceCreateInfo{});
      submit(*cb, *fence);
      wait_for(*fence);
    } catch (const vk::SystemError& e) {
      throw_vulkan_failure(e);
    }
  }

  // vkQueueSubmit of one command buffer signalling `fence`, and
  // vkWaitForFences on one fence without a timeout: through the device's
  // dispatch table, a failure thrown as a VulkanFailure naming the call.
  void submit(vk::CommandBuffer cb, vk::Fence fence) const;
  void wait_for(vk::Fence fence) const;
  // Teardown: waits for the device to finish everything submitted. A lost
  // device has nothing left to wait for, and a destructor cannot report it,
  // so the result is ignored (the failure was reported where it happened).
  void wait_idle_noexcept() const noexcept;

  // A Vulkan-Hpp exception as the renderer's VulkanFailure.
  [[noreturn]] static void throw_vulkan_failure(const vk::SystemError& e);

 private:
  Context() = default;

  std::unique_ptr<ValidationLog> log_ = std::make_unique<ValidationLog>();
  vk::raii::Context loader_;
  vk::raii::Instance instance_{nullptr};
  vk::raii::DebugUtilsMessengerEXT messenger_{nullptr};
  vk::raii::SurfaceKHR surface_{nullptr};  // destroyed before the instance
  vk::raii::PhysicalDevice physical_{nullptr};
  vk::raii::Device device_{nullptr};
  vk::raii::Queue queue_{nullptr};
  vk::raii::CommandPool command_pool_{nullptr};
  std::uint32_t queue_family_ = 0;
  std::string device_name_;
  std::string driver_info_;
  bool software_ = false;
  bool validation_ = false;
  double timestamp_period_ns_ = 1.0;
};

}  // namespace curvlab::renderer
