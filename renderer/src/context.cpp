#include "curvlab/renderer/context.hpp"

#include <cstdlib>
#include <cstring>
#include <iostream>
#include <optional>

namespace curvlab::renderer {

void ValidationLog::add(std::string message) {
  const std::lock_guard lock(mutex_);
  messages_.push_back(std::move(message));
}
std::size_t ValidationLog::count() const {
  const std::lock_guard lock(mutex_);
  return messages_.size();
}
std::vector<std::string> ValidationLog::messages() const {
  const std::lock_guard lock(mutex_);
  return messages_;
}

namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

RenderError device_failure(std::string message) { return {RenderError::Kind::device, std::move(message)}; }

VKAPI_ATTR VkBool32 VKAPI_CALL on_validation_message(
    VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
    const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* log = static_cast<ValidationLog*>(user);
  std::string text = data != nullptr && data->pMessage != nullptr ? data->pMessage : "";
  if (severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
    std::cerr << "vulkan validation: " << text << '\n';
    log->add(std::move(text));
  }
  return VK_FALSE;
}

bool has_layer(const vk::raii::Context& ctx, const char* name) {
  for (const auto& l : ctx.enumerateInstanceLayerProperties())
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

void add_unique(std::vector<const char*>& names, const char* name) {
  for (const char* n : names)
    if (std::strcmp(n, name) == 0) return;
  names.push_back(name);
}

bool has_instance_extension(const vk::raii::Context& ctx, const char* name) {
  for (const auto& e : ctx.enumerateInstanceExtensionProperties())
    if (std::strcmp(e.extensionName, name) == 0) return true;
  // Layers add extensions of their own (the validation layer's debug utils).
  for (const auto& l : ctx.enumerateInstanceLayerProperties())
    for (const auto& e : ctx.enumerateInstanceExtensionProperties(std::string(l.layerName.data())))
      if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

bool has_device_extensions(const vk::raii::PhysicalDevice& pd,
                           const std::vector<const char*>& names) {
  const auto available = pd.enumerateDeviceExtensionProperties();
  for (const char* name : names) {
    bool found = false;
    for (const auto& e : available)
      if (std::strcmp(e.extensionName, name) == 0) found = true;
    if (!found) return false;
  }
  return true;
}

// The first queue family with graphics and compute (and, with a surface,
// presentation to it): one queue does everything, so no ownership transfers.
std::optional<std::uint32_t> usable_queue_family(const vk::raii::PhysicalDevice& pd,
                                                 VkSurfaceKHR surface) {
  const auto families = pd.getQueueFamilyProperties();
  for (std::uint32_t i = 0; i < families.size(); ++i) {
    const auto f = families[i].queueFlags;
    if (!(f & vk::QueueFlagBits::eGraphics) || !(f & vk::QueueFlagBits::eCompute)) continue;
    if (surface != VK_NULL_HANDLE && !pd.getSurfaceSupportKHR(i, surface)) continue;
    return i;
  }
  return std::nullopt;
}

// The instance's layers and extensions: the validation layer's when asked
// for, and the embedder's.
struct InstanceNames {
  std::vector<const char*> layers;
  std::vector<const char*> extensions;
};

std::variant<InstanceNames, RenderError> instance_names(const vk::raii::Context& loader,
                                                        const ContextOptions& options,
                                                        const ContextEmbedding& embedding) {
  InstanceNames names;
  if (options.validation) {
    if (!has_layer(loader, kValidationLayer))
      return device_failure("validation requested but VK_LAYER_KHRONOS_validation is not "
                            "installed (apt-get install vulkan-validationlayers)");
    names.layers.push_back(kValidationLayer);
    names.extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  for (const auto& e : embedding.instance_extensions) {
    if (!has_instance_extension(loader, e.c_str()))
      return device_failure("the Vulkan instance extension " + e +
                            " is not available (a window needs the loader's surface "
                            "extensions: install libvulkan1 and a driver with WSI support)");
    add_unique(names.extensions, e.c_str());
  }
  return names;
}

vk::DebugUtilsMessengerCreateInfoEXT messenger_create_info(ValidationLog* log) {
  return {.messageSeverity = vk::DebugUtilsMessageSeverityFlagBitsEXT::eWarning |
                             vk::DebugUtilsMessageSeverityFlagBitsEXT::eError,
          .messageType = vk::DebugUtilsMessageTypeFlagBitsEXT::eGeneral |
                         vk::DebugUtilsMessageTypeFlagBitsEXT::eValidation |
                         vk::DebugUtilsMessageTypeFlagBitsEXT::ePerformance,
          .pfnUserCallback = &on_validation_message,
          .pUserData = log};
}

// The instance, made by the loader or by the embedder's hook.
std::variant<vk::raii::Instance, RenderError> make_instance(const vk::raii::Context& loader,
                                                            const vk::InstanceCreateInfo& info,
                                                            const ContextHooks& hooks) {
  if (!hooks.create_instance) return vk::raii::Instance(loader, info);
  auto made = hooks.create_instance(static_cast<const VkInstanceCreateInfo&>(info));
  if (auto* e = std::get_if<RenderError>(&made)) return *e;
  return vk::raii::Instance(loader, std::get<VkInstance>(made));
}

// The embedder's device extensions, and the swapchain's with a surface.
std::vector<const char*> device_extension_names(const ContextEmbedding& embedding, bool surface) {
  std::vector<const char*> names;
  for (const auto& e : embedding.device_extensions) add_unique(names, e.c_str());
  if (surface) add_unique(names, VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  return names;
}

// A physical device and the queue family curvlab uses on it.
struct PickedDevice {
  vk::raii::PhysicalDevice physical{nullptr};
  std::uint32_t queue_family = 0;
};

// The device the embedder's hook names, checked for what curvlab needs.
std::variant<PickedDevice, RenderError> embedder_device(const vk::raii::Instance& instance,
                                                        const ContextHooks& hooks,
                                                        const std::vector<const char*>& device_extensions,
                                                        VkSurfaceKHR surface) {
  auto picked = hooks.pick_physical_device(static_cast<VkInstance>(*instance));
  if (auto* e = std::get_if<RenderError>(&picked)) return *e;
  vk::raii::PhysicalDevice physical(instance, std::get<VkPhysicalDevice>(picked));
  const auto props = physical.getProperties();
  if (props.apiVersion < VK_API_VERSION_1_3)
    return device_failure(std::string("the Vulkan device chosen by the embedder (") +
                          props.deviceName.data() +
                          ") does not support Vulkan 1.3, which curvlab needs for dynamic "
                          "rendering; update its driver");
  if (!has_device_extensions(physical, device_extensions))
    return device_failure(std::string("the Vulkan device chosen by the embedder (") +
                          props.deviceName.data() + ") lacks a required device extension");
  const auto family = usable_queue_family(physical, surface);
  if (!family) return device_failure("the Vulkan device has no graphics+compute queue" +
                                     std::string(surface ? " that can present to the window" : ""));
  return PickedDevice{std::move(physical), *family};
}

// How much a device is preferred (higher first); -1: not acceptable.
int device_score(const vk::PhysicalDeviceProperties& props, DeviceChoice choice) {
  const bool cpu = props.deviceType == vk::PhysicalDeviceType::eCpu;
  if (choice == DeviceChoice::software) return cpu ? 1 : -1;
  return props.deviceType == vk::PhysicalDeviceType::eDiscreteGpu     ? 4
         : props.deviceType == vk::PhysicalDeviceType::eIntegratedGpu ? 3
         : cpu                                                        ? 1
                                                                      : 2;
}

// Picks a device: GPUs first unless software is requested; a CPU device
// (lavapipe) is always acceptable. Vulkan 1.3 for dynamic rendering; with a
// surface, a queue that can present to it.
std::variant<PickedDevice, RenderError> best_device(const vk::raii::Instance& instance, DeviceChoice choice,
                                                    const std::vector<const char*>& device_extensions,
                                                    VkSurfaceKHR surface) {
  vk::raii::PhysicalDevices devices(instance);
  PickedDevice best;
  int best_score = -1;
  for (auto& pd : devices) {
    const auto props = pd.getProperties();
    if (props.apiVersion < VK_API_VERSION_1_3) continue;
    if (!has_device_extensions(pd, device_extensions)) continue;
    const auto family = usable_queue_family(pd, surface);
    if (!family) continue;
    const int score = device_score(props, choice);
    if (score > best_score) {
      best_score = score;
      best = PickedDevice{std::move(pd), *family};
    }
  }
  if (best_score >= 0) return best;
  if (surface)
    return device_failure("no Vulkan 1.3 device can present to the window (install a GPU "
                          "driver, or mesa-vulkan-drivers for lavapipe)");
  return device_failure(choice == DeviceChoice::software
                            ? "no CPU Vulkan device found (apt-get install mesa-vulkan-drivers "
                              "for lavapipe)"
                            : "no Vulkan 1.3 device found (install a GPU driver, or "
                              "mesa-vulkan-drivers for lavapipe)");
}

// The driver's name and version, for the session's provenance.
std::string describe_driver(const vk::raii::PhysicalDevice& physical) {
  const auto driver =
      physical.getProperties2<vk::PhysicalDeviceProperties2, vk::PhysicalDeviceDriverProperties>()
          .get<vk::PhysicalDeviceDriverProperties>();
  return std::string(driver.driverName.data()) + " " + driver.driverInfo.data();
}

// The device with one queue of `queue_family`, made by the physical device
// or by the embedder's hook.
std::variant<vk::raii::Device, RenderError> make_device(const vk::raii::PhysicalDevice& physical,
                                                        std::uint32_t queue_family,
                                                        const std::vector<const char*>& extensions,
                                                        const ContextHooks& hooks) {
  const float priority = 1.0f;
  const vk::DeviceQueueCreateInfo queue_info{.queueFamilyIndex = queue_family,
                                             .queueCount = 1,
                                             .pQueuePriorities = &priority};
  vk::PhysicalDeviceVulkan13Features features13{.dynamicRendering = VK_TRUE};
  vk::PhysicalDeviceFeatures2 features{.pNext = &features13};
  features.features.fillModeNonSolid = VK_FALSE;
  const vk::DeviceCreateInfo device_info{
      .pNext = &features,
      .queueCreateInfoCount = 1,
      .pQueueCreateInfos = &queue_info,
      .enabledExtensionCount = static_cast<std::uint32_t>(extensions.size()),
      .ppEnabledExtensionNames = extensions.data()};
  if (!hooks.create_device) return vk::raii::Device(physical, device_info);
  auto made = hooks.create_device(static_cast<VkPhysicalDevice>(*physical),
                                  static_cast<const VkDeviceCreateInfo&>(device_info));
  if (auto* e = std::get_if<RenderError>(&made)) return *e;
  return vk::raii::Device(physical, std::get<VkDevice>(made));
}

}  // namespace

Context::~Context() = default;

std::variant<Context, RenderError> Context::create(const ContextOptions& options) {
  return create(options, ContextEmbedding{});
}

std::variant<Context, RenderError> Context::create(const ContextOptions& options,
                                                   const ContextEmbedding& embedding) {
  Context c;
  try {
    if (c.loader_.enumerateInstanceVersion() < VK_API_VERSION_1_3)
      return device_failure("the Vulkan loader is older than 1.3; install libvulkan1 ≥ 1.3");
    auto names = instance_names(c.loader_, options, embedding);
    if (auto* e = std::get_if<RenderError>(&names)) return *e;
    const auto& [layers, extensions] = std::get<InstanceNames>(names);
    c.validation_ = options.validation;
    const vk::ApplicationInfo app{.pApplicationName = "curvlab",
                                  .applicationVersion = 1,
                                  .pEngineName = "curvlab",
                                  .engineVersion = 1,
                                  .apiVersion = VK_API_VERSION_1_3};
    const vk::DebugUtilsMessengerCreateInfoEXT messenger_info = messenger_create_info(c.log_.get());
    const vk::InstanceCreateInfo instance_info{
        .pNext = options.validation ? &messenger_info : nullptr,
        .pApplicationInfo = &app,
        .enabledLayerCount = static_cast<std::uint32_t>(layers.size()),
        .ppEnabledLayerNames = layers.data(),
        .enabledExtensionCount = static_cast<std::uint32_t>(extensions.size()),
        .ppEnabledExtensionNames = extensions.data()};
    auto instance = make_instance(c.loader_, instance_info, embedding.hooks);
    if (auto* e = std::get_if<RenderError>(&instance)) return *e;
    c.instance_ = std::get<vk::raii::Instance>(std::move(instance));
    if (options.validation)
      c.messenger_ = vk::raii::DebugUtilsMessengerEXT(c.instance_, messenger_info);
    if (embedding.create_surface) {
      auto made = embedding.create_surface(static_cast<VkInstance>(*c.instance_));
      if (auto* e = std::get_if<RenderError>(&made)) return *e;
      c.surface_ = vk::raii::SurfaceKHR(c.instance_, std::get<VkSurfaceKHR>(made));
    }

    const VkSurfaceKHR surface = *c.surface_ ? static_cast<VkSurfaceKHR>(*c.surface_) : VK_NULL_HANDLE;
    const auto device_extensions = device_extension_names(embedding, surface != VK_NULL_HANDLE);
    auto picked = embedding.hooks.pick_physical_device
                      ? embedder_device(c.instance_, embedding.hooks, device_extensions, surface)
                      : best_device(c.instance_, options.device, device_extensions, surface);
    if (auto* e = std::get_if<RenderError>(&picked)) return *e;
    c.physical_ = std::move(std::get<PickedDevice>(picked).physical);
    c.queue_family_ = std::get<PickedDevice>(picked).queue_family;
    const auto props = c.physical_.getProperties();
    c.device_name_ = props.deviceName.data();
    c.software_ = props.deviceType == vk::PhysicalDeviceType::eCpu;
    c.timestamp_period_ns_ = static_cast<double>(props.limits.timestampPeriod);
    c.driver_info_ = describe_driver(c.physical_);

    auto device = make_device(c.physical_, c.queue_family_, device_extensions, embedding.hooks);
    if (auto* e = std::get_if<RenderError>(&device)) return *e;
    c.device_ = std::get<vk::raii::Device>(std::move(device));
    c.queue_ = vk::raii::Queue(c.device_, c.queue_family_, 0);
    c.command_pool_ = vk::raii::CommandPool(
        c.device_, {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                    .queueFamilyIndex = c.queue_family_});
  } catch (const vk::SystemError& e) {
    return device_failure(std::string("Vulkan initialisation failed: ") + e.what());
  }
  return c;
}

void Context::submit(vk::CommandBuffer cb, vk::Fence fence) const {
  const VkCommandBuffer raw = cb;
  VkSubmitInfo info{};
  info.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  info.commandBufferCount = 1;
  info.pCommandBuffers = &raw;
  const VkResult r = device_.getDispatcher()->vkQueueSubmit(static_cast<VkQueue>(*queue_), 1, &info,
                                                            static_cast<VkFence>(fence));
  if (r != VK_SUCCESS) throw VulkanFailure("vkQueueSubmit", r);
}

void Context::wait_for(vk::Fence fence) const {
  const VkFence raw = fence;
  const VkResult r = device_.getDispatcher()->vkWaitForFences(static_cast<VkDevice>(*device_), 1, &raw,
                                                              VK_TRUE, UINT64_MAX);
  if (r != VK_SUCCESS) throw VulkanFailure("vkWaitForFences", r);
}

void Context::wait_idle_noexcept() const noexcept {
  if (!*device_) return;
  // Result ignored on purpose: see the declaration.
  (void)device_.getDispatcher()->vkDeviceWaitIdle(static_cast<VkDevice>(*device_));
}

void Context::throw_vulkan_failure(const vk::SystemError& e) {
  throw VulkanFailure(vk_call_name(e.what()), e.code().value());
}

std::uint32_t Context::memory_type(std::uint32_t type_bits, vk::MemoryPropertyFlags props) const {
  const auto mem = physical_.getMemoryProperties();
  for (std::uint32_t i = 0; i < mem.memoryTypeCount; ++i)
    if ((type_bits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & props) == props) return i;
  std::cerr << "curvlab renderer: no memory type with the requested properties\n";
  std::abort();
}

}  // namespace curvlab::renderer
