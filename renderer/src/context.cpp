#include "curvlab/renderer/context.hpp"

#include <cstdlib>
#include <cstring>
#include <iostream>

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

}  // namespace

Context::~Context() = default;

std::variant<Context, RenderError> Context::create(const ContextOptions& options) {
  Context c;
  try {
    if (c.loader_.enumerateInstanceVersion() < VK_API_VERSION_1_3)
      return RenderError{"the Vulkan loader is older than 1.3; install libvulkan1 ≥ 1.3"};
    std::vector<const char*> layers;
    std::vector<const char*> extensions;
    if (options.validation) {
      if (!has_layer(c.loader_, kValidationLayer))
        return RenderError{"validation requested but VK_LAYER_KHRONOS_validation is not "
                           "installed (apt-get install vulkan-validationlayers)"};
      layers.push_back(kValidationLayer);
      extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
      c.validation_ = true;
    }
    const vk::ApplicationInfo app{.pApplicationName = "curvlab",
                                  .applicationVersion = 1,
                                  .pEngineName = "curvlab",
                                  .engineVersion = 1,
                                  .apiVersion = VK_API_VERSION_1_3};
    const vk::DebugUtilsMessengerCreateInfoEXT messenger_info{
        .messageSeverity = vk::DebugUtilsMessageSeverityFlagBitsEXT::eWarning |
                           vk::DebugUtilsMessageSeverityFlagBitsEXT::eError,
        .messageType = vk::DebugUtilsMessageTypeFlagBitsEXT::eGeneral |
                       vk::DebugUtilsMessageTypeFlagBitsEXT::eValidation |
                       vk::DebugUtilsMessageTypeFlagBitsEXT::ePerformance,
        .pfnUserCallback = &on_validation_message,
        .pUserData = c.log_.get()};
    c.instance_ = vk::raii::Instance(
        c.loader_, vk::InstanceCreateInfo{
                       .pNext = options.validation ? &messenger_info : nullptr,
                       .pApplicationInfo = &app,
                       .enabledLayerCount = static_cast<std::uint32_t>(layers.size()),
                       .ppEnabledLayerNames = layers.data(),
                       .enabledExtensionCount = static_cast<std::uint32_t>(extensions.size()),
                       .ppEnabledExtensionNames = extensions.data()});
    if (options.validation)
      c.messenger_ = vk::raii::DebugUtilsMessengerEXT(c.instance_, messenger_info);

    // Pick a device: GPUs first unless software is requested; a CPU device
    // (lavapipe) is always acceptable. Vulkan 1.3 for dynamic rendering.
    vk::raii::PhysicalDevices devices(c.instance_);
    int best_score = -1;
    for (auto& pd : devices) {
      const auto props = pd.getProperties();
      if (props.apiVersion < VK_API_VERSION_1_3) continue;
      int score = 0;
      const bool cpu = props.deviceType == vk::PhysicalDeviceType::eCpu;
      if (options.device == DeviceChoice::software) {
        if (!cpu) continue;
        score = 1;
      } else {
        score = props.deviceType == vk::PhysicalDeviceType::eDiscreteGpu     ? 4
                : props.deviceType == vk::PhysicalDeviceType::eIntegratedGpu ? 3
                : cpu                                                        ? 1
                                                                             : 2;
      }
      if (score > best_score) {
        best_score = score;
        c.physical_ = std::move(pd);
      }
    }
    if (best_score < 0)
      return RenderError{options.device == DeviceChoice::software
                             ? "no CPU Vulkan device found (apt-get install mesa-vulkan-drivers "
                               "for lavapipe)"
                             : "no Vulkan 1.3 device found (install a GPU driver, or "
                               "mesa-vulkan-drivers for lavapipe)"};
    const auto props = c.physical_.getProperties();
    c.device_name_ = props.deviceName.data();
    c.software_ = props.deviceType == vk::PhysicalDeviceType::eCpu;
    c.timestamp_period_ns_ = static_cast<double>(props.limits.timestampPeriod);
    const auto driver =
        c.physical_.getProperties2<vk::PhysicalDeviceProperties2,
                                   vk::PhysicalDeviceDriverProperties>()
            .get<vk::PhysicalDeviceDriverProperties>();
    c.driver_info_ = std::string(driver.driverName.data()) + " " + driver.driverInfo.data();

    const auto families = c.physical_.getQueueFamilyProperties();
    bool found = false;
    for (std::uint32_t i = 0; i < families.size(); ++i) {
      const auto f = families[i].queueFlags;
      if ((f & vk::QueueFlagBits::eGraphics) && (f & vk::QueueFlagBits::eCompute)) {
        c.queue_family_ = i;
        found = true;
        break;
      }
    }
    if (!found) return RenderError{"the Vulkan device has no graphics+compute queue"};

    const float priority = 1.0f;
    const vk::DeviceQueueCreateInfo queue_info{.queueFamilyIndex = c.queue_family_,
                                               .queueCount = 1,
                                               .pQueuePriorities = &priority};
    vk::PhysicalDeviceVulkan13Features features13{.dynamicRendering = VK_TRUE};
    vk::PhysicalDeviceFeatures2 features{.pNext = &features13};
    features.features.fillModeNonSolid = VK_FALSE;
    c.device_ = vk::raii::Device(c.physical_, vk::DeviceCreateInfo{.pNext = &features,
                                                                  .queueCreateInfoCount = 1,
                                                                  .pQueueCreateInfos = &queue_info});
    c.queue_ = vk::raii::Queue(c.device_, c.queue_family_, 0);
    c.command_pool_ = vk::raii::CommandPool(
        c.device_, {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                    .queueFamilyIndex = c.queue_family_});
  } catch (const vk::SystemError& e) {
    return RenderError{std::string("Vulkan initialisation failed: ") + e.what()};
  }
  return c;
}

std::uint32_t Context::memory_type(std::uint32_t type_bits, vk::MemoryPropertyFlags props) const {
  const auto mem = physical_.getMemoryProperties();
  for (std::uint32_t i = 0; i < mem.memoryTypeCount; ++i)
    if ((type_bits & (1u << i)) && (mem.memoryTypes[i].propertyFlags & props) == props) return i;
  std::cerr << "curvlab renderer: no memory type with the requested properties\n";
  std::abort();
}

}  // namespace curvlab::renderer
