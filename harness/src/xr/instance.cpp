#include "curvlab/harness/xr/instance.hpp"

#include <openxr/openxr_reflection.h>

#include <algorithm>
#include <cstring>

namespace curvlab::harness::xr {
namespace {

constexpr const char* kVulkanEnable2 = "XR_KHR_vulkan_enable2";

std::string hint(XrResult result) {
  switch (result) {
    case XR_ERROR_RUNTIME_UNAVAILABLE:
    case XR_ERROR_RUNTIME_FAILURE:
    case XR_ERROR_INSTANCE_LOST:
#ifdef _WIN32
      // Where the Windows loader looks (docs/windows.md).
      return "no OpenXR runtime is installed and active. Install and start one: SteamVR (start "
             "it and make it the OpenXR runtime in its settings), Meta Quest Link, or the headset "
             "vendor's runtime; it registers itself in the registry under "
             "HKEY_LOCAL_MACHINE\\SOFTWARE\\Khronos\\OpenXR\\1\\ActiveRuntime (XR_RUNTIME_JSON "
             "chooses one explicitly, except from an elevated, administrator console). For "
             "piloting without a headset use --backend desktop";
#else
      return "no OpenXR runtime is installed and active. Install and start one: Monado "
             "(not packaged in Debian 12: build it or use a distribution that packages it, then "
             "run `monado-service`), SteamVR (start it and "
             "make it the OpenXR runtime in its settings), or the headset vendor's runtime. "
             "Its installer registers it in /etc/xdg/openxr/1/active_runtime.json (or "
             "~/.config/openxr/1/active_runtime.json); to choose one explicitly, set "
             "XR_RUNTIME_JSON=/path/to/its/manifest.json. For piloting without a headset use "
             "--backend desktop";
#endif
    case XR_ERROR_FORM_FACTOR_UNAVAILABLE:
      return "the runtime is running but no headset is available: connect the headset, "
             "switch it on and put it on once to wake it, then retry";
    case XR_ERROR_EXTENSION_NOT_PRESENT:
      return "the OpenXR runtime does not offer XR_KHR_vulkan_enable2, which curvlab needs "
             "to render with Vulkan; update the runtime or use one that supports it";
    case XR_ERROR_API_VERSION_UNSUPPORTED:
      return "the runtime does not support OpenXR 1.0; update the runtime";
    default:
      return "see the runtime's log for details";
  }
}

harness::Error failure(XrResult result, const char* call) {
  const bool missing = result == XR_ERROR_RUNTIME_UNAVAILABLE || result == XR_ERROR_RUNTIME_FAILURE ||
                       result == XR_ERROR_FORM_FACTOR_UNAVAILABLE ||
                       result == XR_ERROR_EXTENSION_NOT_PRESENT || result == XR_ERROR_API_VERSION_UNSUPPORTED;
  return {missing ? harness::Error::Kind::device : harness::Error::Kind::api,
          std::string(call) + " returned " + result_name(result) + " (" +
              std::to_string(static_cast<int>(result)) + "): " + hint(result)};
}

std::string version_string(XrVersion v) {
  return std::to_string(XR_VERSION_MAJOR(v)) + "." + std::to_string(XR_VERSION_MINOR(v)) + "." +
         std::to_string(XR_VERSION_PATCH(v));
}

}  // namespace

std::string result_name(XrResult result) {
  // The SDK's reflection list names every XrResult of the headers we build
  // against; this needs no instance, unlike xrResultToString.
#define CURVLAB_XR_RESULT_CASE(name, value) \
  case name:                                \
    return #name;
  switch (result) {
    XR_LIST_ENUM_XrResult(CURVLAB_XR_RESULT_CASE)
    default:
      break;
  }
#undef CURVLAB_XR_RESULT_CASE
  return "XR_RESULT_" + std::to_string(static_cast<int>(result));
}

harness::Error failure_of(XrResult result, const char* call) { return failure(result, call); }

std::optional<FailedCall> failed_call(const harness::Error& error) {
  // "CALL returned NAME (CODE): …", as failure() writes it.
  const std::string& m = error.message;
  const auto returned = m.find(" returned ");
  const auto open = m.find(" (", returned == std::string::npos ? 0 : returned);
  const auto close = m.find("):", open == std::string::npos ? 0 : open);
  if (returned == std::string::npos || open == std::string::npos || close == std::string::npos)
    return std::nullopt;
  try {
    return FailedCall{m.substr(0, returned), static_cast<XrResult>(std::stoi(m.substr(open + 2, close - open - 2)))};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

harness::Result<std::vector<std::string>> available_extensions() {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateInstanceExtensionProperties(nullptr, 0, &count, nullptr);
      XR_FAILED(r))
    return failure(r, "xrEnumerateInstanceExtensionProperties");
  std::vector<XrExtensionProperties> extensions(
      count, tagged<XrExtensionProperties>(XR_TYPE_EXTENSION_PROPERTIES));
  if (count > 0) {
    if (const XrResult r =
            xrEnumerateInstanceExtensionProperties(nullptr, count, &count, extensions.data());
        XR_FAILED(r))
      return failure(r, "xrEnumerateInstanceExtensionProperties");
  }
  std::vector<std::string> names;
  for (std::uint32_t i = 0; i < count; ++i) names.emplace_back(extensions[i].extensionName);
  return names;
}

harness::Result<Instance> Instance::create(const std::string& application_name) {
  return create(application_name, {});
}

harness::Result<Instance> Instance::create(const std::string& application_name,
                                           const std::vector<std::string>& extra_extensions) {
  auto info = tagged<XrInstanceCreateInfo>(XR_TYPE_INSTANCE_CREATE_INFO);
  std::strncpy(info.applicationInfo.applicationName, application_name.c_str(),
               XR_MAX_APPLICATION_NAME_SIZE - 1);
  info.applicationInfo.applicationVersion = 1;
  std::strncpy(info.applicationInfo.engineName, "curvlab", XR_MAX_ENGINE_NAME_SIZE - 1);
  info.applicationInfo.engineVersion = 1;
  info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  std::vector<const char*> extensions{kVulkanEnable2};
  for (const auto& e : extra_extensions) extensions.push_back(e.c_str());
  info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
  info.enabledExtensionNames = extensions.data();
  XrInstance instance = XR_NULL_HANDLE;
  const XrResult r = xrCreateInstance(&info, &instance);
  if (XR_FAILED(r)) return failure(r, "xrCreateInstance");
  return Instance(instance);
}

Instance::Instance(Instance&& other) noexcept : instance_(other.instance_) {
  other.instance_ = XR_NULL_HANDLE;
}

Instance& Instance::operator=(Instance&& other) noexcept {
  if (this != &other) {
    Instance old(std::move(*this));
    instance_ = other.instance_;
    other.instance_ = XR_NULL_HANDLE;
  }
  return *this;
}

Instance::~Instance() {
  if (instance_ != XR_NULL_HANDLE) xrDestroyInstance(instance_);
}

harness::Result<XrSystemId> Instance::hmd_system() const {
  auto info = tagged<XrSystemGetInfo>(XR_TYPE_SYSTEM_GET_INFO);
  info.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  const XrResult r = xrGetSystem(instance_, &info, &system);
  if (XR_FAILED(r)) return failure(r, "xrGetSystem");
  return system;
}

std::string Instance::path_string(XrPath path) const {
  char buffer[XR_MAX_PATH_LENGTH];
  std::uint32_t n = 0;
  if (XR_FAILED(xrPathToString(instance_, path, sizeof buffer, &n, buffer))) return "";
  return buffer;
}

harness::Result<ActionSet> ActionSet::create(const Instance& instance, const ActionSetDef& def) {
  ActionSet out;
  auto set_info = tagged<XrActionSetCreateInfo>(XR_TYPE_ACTION_SET_CREATE_INFO);
  std::strncpy(set_info.actionSetName, def.name.c_str(), XR_MAX_ACTION_SET_NAME_SIZE - 1);
  std::strncpy(set_info.localizedActionSetName, def.localized_name.c_str(),
               XR_MAX_LOCALIZED_ACTION_SET_NAME_SIZE - 1);
  set_info.priority = def.priority;
  if (const XrResult r = xrCreateActionSet(instance.handle(), &set_info, &out.set_); XR_FAILED(r))
    return failure(r, "xrCreateActionSet");

  auto to_path = [&](const std::string& text, XrPath* path) {
    return xrStringToPath(instance.handle(), text.c_str(), path);
  };
  for (const auto& a : def.actions) {
    std::vector<XrPath> subactions(a.subaction_paths.size());
    for (std::size_t i = 0; i < subactions.size(); ++i)
      if (const XrResult r = to_path(a.subaction_paths[i], &subactions[i]); XR_FAILED(r))
        return failure(r, "xrStringToPath");
    auto info = tagged<XrActionCreateInfo>(XR_TYPE_ACTION_CREATE_INFO);
    std::strncpy(info.actionName, a.name.c_str(), XR_MAX_ACTION_NAME_SIZE - 1);
    std::strncpy(info.localizedActionName, a.localized_name.c_str(),
                 XR_MAX_LOCALIZED_ACTION_NAME_SIZE - 1);
    info.actionType = a.type == ActionType::Pose      ? XR_ACTION_TYPE_POSE_INPUT
                      : a.type == ActionType::Float   ? XR_ACTION_TYPE_FLOAT_INPUT
                                                      : XR_ACTION_TYPE_BOOLEAN_INPUT;
    info.countSubactionPaths = static_cast<std::uint32_t>(subactions.size());
    info.subactionPaths = subactions.data();
    XrAction action = XR_NULL_HANDLE;
    if (const XrResult r = xrCreateAction(out.set_, &info, &action); XR_FAILED(r))
      return failure(r, "xrCreateAction");
    out.actions_.emplace_back(a.name, action);
  }
  for (const auto& profile : def.profiles) {
    std::vector<XrActionSuggestedBinding> bindings;
    for (const auto& b : profile.bindings) {
      XrActionSuggestedBinding s{out.action(b.action), XR_NULL_PATH};
      if (const XrResult r = to_path(b.path, &s.binding); XR_FAILED(r))
        return failure(r, "xrStringToPath");
      bindings.push_back(s);
    }
    auto suggested = tagged<XrInteractionProfileSuggestedBinding>(XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING);
    if (const XrResult r = to_path(profile.profile, &suggested.interactionProfile); XR_FAILED(r))
      return failure(r, "xrStringToPath");
    suggested.countSuggestedBindings = static_cast<std::uint32_t>(bindings.size());
    suggested.suggestedBindings = bindings.data();
    if (const XrResult r = xrSuggestInteractionProfileBindings(instance.handle(), &suggested);
        XR_FAILED(r))
      return failure(r, "xrSuggestInteractionProfileBindings");
  }
  return out;
}

ActionSet::ActionSet(ActionSet&& other) noexcept
    : set_(other.set_), actions_(std::move(other.actions_)) {
  other.set_ = XR_NULL_HANDLE;
}

ActionSet& ActionSet::operator=(ActionSet&& other) noexcept {
  if (this != &other) {
    ActionSet old(std::move(*this));
    set_ = other.set_;
    actions_ = std::move(other.actions_);
    other.set_ = XR_NULL_HANDLE;
  }
  return *this;
}

ActionSet::~ActionSet() {
  // Destroying the set destroys its actions (OpenXR: child handles).
  if (set_ != XR_NULL_HANDLE) xrDestroyActionSet(set_);
}

XrAction ActionSet::action(std::string_view name) const {
  for (const auto& [n, a] : actions_)
    if (n == name) return a;
  return XR_NULL_HANDLE;
}

harness::Result<ProbeReport> probe(const std::string& application_name) {
  ProbeReport report;
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateApiLayerProperties(0, &count, nullptr); XR_FAILED(r))
    return failure(r, "xrEnumerateApiLayerProperties");
  std::vector<XrApiLayerProperties> layers(
      count, tagged<XrApiLayerProperties>(XR_TYPE_API_LAYER_PROPERTIES));
  if (count > 0) {
    if (const XrResult r = xrEnumerateApiLayerProperties(count, &count, layers.data()); XR_FAILED(r))
      return failure(r, "xrEnumerateApiLayerProperties");
  }
  for (std::uint32_t i = 0; i < count; ++i) report.api_layers.emplace_back(layers[i].layerName);

  // The runtime provides the extension list, so this is where a missing
  // runtime first shows.
  auto extensions = available_extensions();
  if (!extensions) return extensions.error();
  report.extensions = std::move(extensions).value();
  if (std::find(report.extensions.begin(), report.extensions.end(), kVulkanEnable2) ==
      report.extensions.end())
    return failure(XR_ERROR_EXTENSION_NOT_PRESENT, "xrEnumerateInstanceExtensionProperties");

  auto created = Instance::create(application_name);
  if (!created) return created.error();
  const Instance& instance = created.value();

  auto props = tagged<XrInstanceProperties>(XR_TYPE_INSTANCE_PROPERTIES);
  if (const XrResult r = xrGetInstanceProperties(instance.handle(), &props); XR_FAILED(r))
    return failure(r, "xrGetInstanceProperties");
  report.runtime_name = props.runtimeName;
  report.runtime_version = version_string(props.runtimeVersion);

  auto system = instance.hmd_system();
  if (!system) return system.error();
  auto sys = tagged<XrSystemProperties>(XR_TYPE_SYSTEM_PROPERTIES);
  if (const XrResult r = xrGetSystemProperties(instance.handle(), system.value(), &sys);
      XR_FAILED(r))
    return failure(r, "xrGetSystemProperties");
  report.system_name = sys.systemName;
  report.vendor_id = sys.vendorId;
  report.orientation_tracking = sys.trackingProperties.orientationTracking == XR_TRUE;
  report.position_tracking = sys.trackingProperties.positionTracking == XR_TRUE;
  report.max_swapchain_width = sys.graphicsProperties.maxSwapchainImageWidth;
  report.max_swapchain_height = sys.graphicsProperties.maxSwapchainImageHeight;
  return report;
}

}  // namespace curvlab::harness::xr
