// The test runtime refuses what the OpenXR specification forbids, so a
// session that passes through it has followed those rules: each misuse here
// gets the specification's error (and a "violation" line in the log).
// Through the real loader, with a Vulkan device on lavapipe made by the
// runtime.
#include <time.h>

#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>

#include "runtime/loader_interface.hpp"

#include <gtest/gtest.h>

#include <dlfcn.h>

#include <array>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace {

template <class T>
T tagged(XrStructureType type) {
  T v{};
  v.type = type;
  return v;
}

template <class F>
void load(XrInstance instance, const char* name, F& fn) {
  ASSERT_EQ(xrGetInstanceProcAddr(instance, name, reinterpret_cast<PFN_xrVoidFunction*>(&fn)), XR_SUCCESS) << name;
}

// An instance, the Vulkan objects made through the runtime, a session and
// its STAGE space; torn down in reverse.
class RuntimeRules : public ::testing::Test {
 protected:
  void SetUp() override {
    log_ = std::filesystem::temp_directory_path() / ("curvlab_xr_rules_" + std::to_string(::getpid()) + ".log");
    std::filesystem::remove(log_);
    setenv("XR_RUNTIME_JSON", CURVLAB_TEST_XR_RUNTIME_JSON, 1);
    setenv("CURVLAB_TEST_XR_LOG", log_.c_str(), 1);
    auto info = tagged<XrInstanceCreateInfo>(XR_TYPE_INSTANCE_CREATE_INFO);
    std::strcpy(info.applicationInfo.applicationName, "rules");
    info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
    const char* ext[] = {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME, XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME};
    info.enabledExtensionCount = 2;
    info.enabledExtensionNames = ext;
    ASSERT_EQ(xrCreateInstance(&info, &instance_), XR_SUCCESS);
    auto sys = tagged<XrSystemGetInfo>(XR_TYPE_SYSTEM_GET_INFO);
    sys.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    ASSERT_EQ(xrGetSystem(instance_, &sys, &system_), XR_SUCCESS);

    PFN_xrGetVulkanGraphicsRequirements2KHR requirements = nullptr;
    PFN_xrCreateVulkanInstanceKHR create_instance = nullptr;
    PFN_xrGetVulkanGraphicsDevice2KHR get_device = nullptr;
    PFN_xrCreateVulkanDeviceKHR create_device = nullptr;
    load(instance_, "xrGetVulkanGraphicsRequirements2KHR", requirements);
    load(instance_, "xrCreateVulkanInstanceKHR", create_instance);
    load(instance_, "xrGetVulkanGraphicsDevice2KHR", get_device);
    load(instance_, "xrCreateVulkanDeviceKHR", create_device);
    VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO, nullptr, "rules", 1, "rules", 1, VK_API_VERSION_1_1};
    VkInstanceCreateInfo vi{};
    vi.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
    vi.pApplicationInfo = &app;
    auto xi = tagged<XrVulkanInstanceCreateInfoKHR>(XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR);
    xi.systemId = system_;
    xi.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
    xi.vulkanCreateInfo = &vi;
    VkResult vr = VK_SUCCESS;
    // Before the graphics requirements were asked for: refused.
    EXPECT_EQ(create_instance(instance_, &xi, &vk_instance_, &vr), XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING);
    auto req = tagged<XrGraphicsRequirementsVulkan2KHR>(XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR);
    ASSERT_EQ(requirements(instance_, system_, &req), XR_SUCCESS);
    ASSERT_EQ(create_instance(instance_, &xi, &vk_instance_, &vr), XR_SUCCESS);
    ASSERT_EQ(vr, VK_SUCCESS);
    auto gi = tagged<XrVulkanGraphicsDeviceGetInfoKHR>(XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR);
    gi.systemId = system_;
    gi.vulkanInstance = vk_instance_;
    ASSERT_EQ(get_device(instance_, &gi, &physical_), XR_SUCCESS);
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo qi{};
    qi.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
    qi.queueFamilyIndex = 0;
    qi.queueCount = 1;
    qi.pQueuePriorities = &priority;
    VkDeviceCreateInfo di{};
    di.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
    di.queueCreateInfoCount = 1;
    di.pQueueCreateInfos = &qi;
    auto xd = tagged<XrVulkanDeviceCreateInfoKHR>(XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR);
    xd.systemId = system_;
    xd.pfnGetInstanceProcAddr = &vkGetInstanceProcAddr;
    xd.vulkanPhysicalDevice = physical_;
    xd.vulkanCreateInfo = &di;
    ASSERT_EQ(create_device(instance_, &xd, &device_, &vr), XR_SUCCESS);
    ASSERT_EQ(vr, VK_SUCCESS);

    auto binding = tagged<XrGraphicsBindingVulkan2KHR>(XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR);
    binding.instance = vk_instance_;
    binding.physicalDevice = physical_;
    binding.device = device_;
    auto si = tagged<XrSessionCreateInfo>(XR_TYPE_SESSION_CREATE_INFO);
    si.next = &binding;
    si.systemId = system_;
    ASSERT_EQ(xrCreateSession(instance_, &si, &session_), XR_SUCCESS);
    auto space = tagged<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
    space.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
    space.poseInReferenceSpace.orientation.w = 1.0f;
    ASSERT_EQ(xrCreateReferenceSpace(session_, &space, &stage_), XR_SUCCESS);
  }

  void TearDown() override {
    if (session_ != XR_NULL_HANDLE) xrDestroySession(session_);
    if (device_ != VK_NULL_HANDLE) vkDestroyDevice(device_, nullptr);
    if (vk_instance_ != VK_NULL_HANDLE) vkDestroyInstance(vk_instance_, nullptr);
    if (instance_ != XR_NULL_HANDLE) xrDestroyInstance(instance_);
    unsetenv("XR_RUNTIME_JSON");
    unsetenv("CURVLAB_TEST_XR_LOG");
    std::filesystem::remove(log_);
  }

  int violations() const {
    std::ifstream in(log_);
    int n = 0;
    for (std::string line; std::getline(in, line);) n += line.rfind("violation ", 0) == 0 ? 1 : 0;
    return n;
  }

  XrSwapchain swapchain() {
    auto info = tagged<XrSwapchainCreateInfo>(XR_TYPE_SWAPCHAIN_CREATE_INFO);
    info.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT;
    info.format = VK_FORMAT_R8G8B8A8_UNORM;
    info.sampleCount = info.faceCount = info.arraySize = info.mipCount = 1;
    info.width = info.height = 64;
    XrSwapchain sc = XR_NULL_HANDLE;
    EXPECT_EQ(xrCreateSwapchain(session_, &info, &sc), XR_SUCCESS);
    return sc;
  }

  XrPath path(const char* text) {
    XrPath p = XR_NULL_PATH;
    EXPECT_EQ(xrStringToPath(instance_, text, &p), XR_SUCCESS) << text;
    return p;
  }

  // An action set like a game's: a grab value, a hand pose and a vibration
  // for either hand.
  struct HandActions {
    XrActionSet set = XR_NULL_HANDLE;
    std::array<XrPath, 2> hands{};
    XrAction grab = XR_NULL_HANDLE, pose = XR_NULL_HANDLE, buzz = XR_NULL_HANDLE;
  };
  HandActions hand_actions() {
    HandActions h;
    auto si = tagged<XrActionSetCreateInfo>(XR_TYPE_ACTION_SET_CREATE_INFO);
    std::strcpy(si.actionSetName, "hands");
    std::strcpy(si.localizedActionSetName, "Hands");
    EXPECT_EQ(xrCreateActionSet(instance_, &si, &h.set), XR_SUCCESS);
    h.hands = {path("/user/hand/left"), path("/user/hand/right")};
    auto action = [&h](const char* name, XrActionType type) {
      auto ai = tagged<XrActionCreateInfo>(XR_TYPE_ACTION_CREATE_INFO);
      std::strcpy(ai.actionName, name);
      std::strcpy(ai.localizedActionName, name);
      ai.actionType = type;
      ai.countSubactionPaths = 2;
      ai.subactionPaths = h.hands.data();
      XrAction a = XR_NULL_HANDLE;
      EXPECT_EQ(xrCreateAction(h.set, &ai, &a), XR_SUCCESS) << name;
      return a;
    };
    h.grab = action("grab", XR_ACTION_TYPE_FLOAT_INPUT);
    h.pose = action("pose", XR_ACTION_TYPE_POSE_INPUT);
    h.buzz = action("buzz", XR_ACTION_TYPE_VIBRATION_OUTPUT);
    return h;
  }

  XrResult suggest(const char* profile, std::vector<XrActionSuggestedBinding> bindings) {
    auto s = tagged<XrInteractionProfileSuggestedBinding>(XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING);
    s.interactionProfile = path(profile);
    s.countSuggestedBindings = static_cast<std::uint32_t>(bindings.size());
    s.suggestedBindings = bindings.data();
    return xrSuggestInteractionProfileBindings(instance_, &s);
  }

  XrResult suggest_touch(const HandActions& h) {
    return suggest("/interaction_profiles/oculus/touch_controller",
                   {{h.grab, path("/user/hand/left/input/squeeze/value")},
                    {h.grab, path("/user/hand/right/input/squeeze/value")},
                    {h.pose, path("/user/hand/right/input/grip/pose")},
                    {h.buzz, path("/user/hand/right/output/haptic")}});
  }

  void attach(XrActionSet set) {
    auto info = tagged<XrSessionActionSetsAttachInfo>(XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO);
    info.countActionSets = 1;
    info.actionSets = &set;
    ASSERT_EQ(xrAttachSessionActionSets(session_, &info), XR_SUCCESS);
  }

  std::filesystem::path log_;
  XrInstance instance_ = XR_NULL_HANDLE;
  XrSystemId system_ = XR_NULL_SYSTEM_ID;
  VkInstance vk_instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  XrSession session_ = XR_NULL_HANDLE;
  XrSpace stage_ = XR_NULL_HANDLE;
};

TEST_F(RuntimeRules, SessionAndFrameLoopOrder) {
  auto wait = tagged<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
  auto state = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  auto begin = tagged<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
  auto end = tagged<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
  end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  EXPECT_EQ(xrWaitFrame(session_, &wait, &state), XR_ERROR_SESSION_NOT_RUNNING);
  // IDLE, READY arrive first.
  auto event = tagged<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
  ASSERT_EQ(xrPollEvent(instance_, &event), XR_SUCCESS);
  EXPECT_EQ(reinterpret_cast<XrEventDataSessionStateChanged*>(&event)->state, XR_SESSION_STATE_IDLE);
  event = tagged<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
  ASSERT_EQ(xrPollEvent(instance_, &event), XR_SUCCESS);
  EXPECT_EQ(reinterpret_cast<XrEventDataSessionStateChanged*>(&event)->state, XR_SESSION_STATE_READY);
  auto bi = tagged<XrSessionBeginInfo>(XR_TYPE_SESSION_BEGIN_INFO);
  bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  ASSERT_EQ(xrBeginSession(session_, &bi), XR_SUCCESS);
  EXPECT_EQ(xrBeginSession(session_, &bi), XR_ERROR_SESSION_RUNNING);
  EXPECT_EQ(xrEndSession(session_), XR_ERROR_SESSION_NOT_STOPPING);
  EXPECT_EQ(xrBeginFrame(session_, &begin), XR_ERROR_CALL_ORDER_INVALID);
  EXPECT_EQ(xrEndFrame(session_, &end), XR_ERROR_CALL_ORDER_INVALID);
  ASSERT_EQ(xrWaitFrame(session_, &wait, &state), XR_SUCCESS);
  EXPECT_GT(state.predictedDisplayTime, 0);
  EXPECT_EQ(state.predictedDisplayPeriod, 11'111'111);
  ASSERT_EQ(xrBeginFrame(session_, &begin), XR_SUCCESS);
  end.displayTime = state.predictedDisplayTime;
  end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_ADDITIVE;
  EXPECT_EQ(xrEndFrame(session_, &end), XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED);
  // The next frame is one period later on the display's grid.
  const XrTime first = state.predictedDisplayTime;
  ASSERT_EQ(xrWaitFrame(session_, &wait, &state), XR_SUCCESS);
  EXPECT_EQ((state.predictedDisplayTime - first) % state.predictedDisplayPeriod, 0);
  EXPECT_GT(state.predictedDisplayTime, first);
  // A second xrWaitFrame before xrBeginFrame: a runtime blocks it until the
  // frame is begun (forever, on one thread); this one refuses it.
  auto again = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  EXPECT_EQ(xrWaitFrame(session_, &wait, &again), XR_ERROR_CALL_ORDER_INVALID);
  ASSERT_EQ(xrBeginFrame(session_, &begin), XR_SUCCESS);
  end.displayTime = state.predictedDisplayTime;
  end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  EXPECT_EQ(xrEndFrame(session_, &end), XR_SUCCESS);

  // XR_KHR_convert_timespec_time: XrTime is CLOCK_MONOTONIC less an epoch.
  PFN_xrConvertTimeToTimespecTimeKHR to_ts = nullptr;
  PFN_xrConvertTimespecTimeToTimeKHR from_ts = nullptr;
  load(instance_, "xrConvertTimeToTimespecTimeKHR", to_ts);
  load(instance_, "xrConvertTimespecTimeToTimeKHR", from_ts);
  timespec ts{};
  ASSERT_EQ(to_ts(instance_, state.predictedDisplayTime, &ts), XR_SUCCESS);
  XrTime back = 0;
  ASSERT_EQ(from_ts(instance_, &ts, &back), XR_SUCCESS);
  EXPECT_EQ(back, state.predictedDisplayTime);
  EXPECT_NE(std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec, state.predictedDisplayTime);
  EXPECT_EQ(violations(), 8);  // with the one in SetUp
}

TEST_F(RuntimeRules, SwapchainImagesAndLayers) {
  const XrSwapchain left = swapchain();
  const XrSwapchain right = swapchain();
  auto acquire = tagged<XrSwapchainImageAcquireInfo>(XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO);
  auto wait = tagged<XrSwapchainImageWaitInfo>(XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO);
  wait.timeout = XR_INFINITE_DURATION;
  auto release = tagged<XrSwapchainImageReleaseInfo>(XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO);
  std::uint32_t index = 0;
  EXPECT_EQ(xrWaitSwapchainImage(left, &wait), XR_ERROR_CALL_ORDER_INVALID);
  EXPECT_EQ(xrReleaseSwapchainImage(left, &release), XR_ERROR_CALL_ORDER_INVALID);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(xrAcquireSwapchainImage(left, &acquire, &index), XR_SUCCESS);
  EXPECT_EQ(xrAcquireSwapchainImage(left, &acquire, &index), XR_ERROR_CALL_ORDER_INVALID);
  EXPECT_EQ(xrReleaseSwapchainImage(left, &release), XR_ERROR_CALL_ORDER_INVALID);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(xrWaitSwapchainImage(left, &wait), XR_SUCCESS);
    EXPECT_EQ(xrWaitSwapchainImage(left, &wait), XR_ERROR_CALL_ORDER_INVALID) << "waited twice";
    EXPECT_EQ(xrReleaseSwapchainImage(left, &release), XR_SUCCESS);
  }

  auto bi = tagged<XrSessionBeginInfo>(XR_TYPE_SESSION_BEGIN_INFO);
  bi.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
  ASSERT_EQ(xrBeginSession(session_, &bi), XR_SUCCESS);
  std::array<XrCompositionLayerProjectionView, 2> views{};
  for (std::size_t i = 0; i < 2; ++i) {
    views[i] = tagged<XrCompositionLayerProjectionView>(XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW);
    views[i].pose.orientation.w = 1.0f;
    views[i].fov = {-0.8f, 0.8f, 0.8f, -0.8f};
    views[i].subImage.swapchain = i == 0 ? left : right;
    views[i].subImage.imageRect = {{0, 0}, {64, 64}};
  }
  auto layer = tagged<XrCompositionLayerProjection>(XR_TYPE_COMPOSITION_LAYER_PROJECTION);
  layer.space = stage_;
  layer.viewCount = 2;
  layer.views = views.data();
  const auto* header = reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer);
  auto submit = [&]() {
    auto fw = tagged<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
    auto state = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
    auto fb = tagged<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
    EXPECT_EQ(xrWaitFrame(session_, &fw, &state), XR_SUCCESS);
    EXPECT_EQ(xrBeginFrame(session_, &fb), XR_SUCCESS);
    auto end = tagged<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
    end.displayTime = state.predictedDisplayTime;
    end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    end.layerCount = 1;
    end.layers = &header;
    return xrEndFrame(session_, &end);
  };
  // The right swapchain never released an image.
  EXPECT_EQ(submit(), XR_ERROR_LAYER_INVALID);
  ASSERT_EQ(xrAcquireSwapchainImage(right, &acquire, &index), XR_SUCCESS);
  ASSERT_EQ(xrWaitSwapchainImage(right, &wait), XR_SUCCESS);
  ASSERT_EQ(xrReleaseSwapchainImage(right, &release), XR_SUCCESS);
  EXPECT_EQ(submit(), XR_SUCCESS);
  // An image still held when the frame ends.
  ASSERT_EQ(xrAcquireSwapchainImage(left, &acquire, &index), XR_SUCCESS);
  EXPECT_EQ(submit(), XR_ERROR_LAYER_INVALID);
  ASSERT_EQ(xrWaitSwapchainImage(left, &wait), XR_SUCCESS);
  ASSERT_EQ(xrReleaseSwapchainImage(left, &release), XR_SUCCESS);
  layer.viewCount = 1;
  EXPECT_EQ(submit(), XR_ERROR_VALIDATION_FAILURE);
  layer.viewCount = 2;
  views[1].subImage.imageRect = {{32, 0}, {64, 64}};
  EXPECT_EQ(submit(), XR_ERROR_SWAPCHAIN_RECT_INVALID);
  views[1].subImage.imageRect = {{0, 0}, {64, 64}};
  views[0].pose.orientation.w = 2.0f;
  EXPECT_EQ(submit(), XR_ERROR_POSE_INVALID);
  views[0].pose.orientation.w = 1.0f;
  EXPECT_EQ(submit(), XR_SUCCESS);
  EXPECT_EQ(violations(), 13);  // with the one in SetUp
  xrDestroySwapchain(left);
  xrDestroySwapchain(right);
}

TEST_F(RuntimeRules, ActionsAndBindings) {
  auto si = tagged<XrActionSetCreateInfo>(XR_TYPE_ACTION_SET_CREATE_INFO);
  std::strcpy(si.actionSetName, "rules");
  std::strcpy(si.localizedActionSetName, "Rules");
  XrActionSet set = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateActionSet(instance_, &si, &set), XR_SUCCESS);
  XrPath right = XR_NULL_PATH, left = XR_NULL_PATH, touch = XR_NULL_PATH, a_click = XR_NULL_PATH, bogus = XR_NULL_PATH;
  ASSERT_EQ(xrStringToPath(instance_, "/user/hand/right", &right), XR_SUCCESS);
  ASSERT_EQ(xrStringToPath(instance_, "/user/hand/left", &left), XR_SUCCESS);
  ASSERT_EQ(xrStringToPath(instance_, "/interaction_profiles/oculus/touch_controller", &touch), XR_SUCCESS);
  ASSERT_EQ(xrStringToPath(instance_, "/user/hand/right/input/a/click", &a_click), XR_SUCCESS);
  ASSERT_EQ(xrStringToPath(instance_, "/user/hand/right/input/q/click", &bogus), XR_SUCCESS);
  XrPath bad = XR_NULL_PATH;
  EXPECT_EQ(xrStringToPath(instance_, "/User//hand", &bad), XR_ERROR_PATH_FORMAT_INVALID);
  char text[XR_MAX_PATH_LENGTH];
  std::uint32_t n = 0;
  ASSERT_EQ(xrPathToString(instance_, a_click, sizeof text, &n, text), XR_SUCCESS);
  EXPECT_STREQ(text, "/user/hand/right/input/a/click");

  auto ai = tagged<XrActionCreateInfo>(XR_TYPE_ACTION_CREATE_INFO);
  std::strcpy(ai.actionName, "press");
  std::strcpy(ai.localizedActionName, "Press");
  ai.actionType = XR_ACTION_TYPE_BOOLEAN_INPUT;
  ai.countSubactionPaths = 1;
  ai.subactionPaths = &right;
  XrAction press = XR_NULL_HANDLE;
  ASSERT_EQ(xrCreateAction(set, &ai, &press), XR_SUCCESS);
  EXPECT_EQ(xrCreateAction(set, &ai, &press), XR_ERROR_NAME_DUPLICATED);

  XrActionSuggestedBinding binding{press, bogus};
  auto suggested = tagged<XrInteractionProfileSuggestedBinding>(XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING);
  suggested.interactionProfile = touch;
  suggested.countSuggestedBindings = 1;
  suggested.suggestedBindings = &binding;
  EXPECT_EQ(xrSuggestInteractionProfileBindings(instance_, &suggested), XR_ERROR_PATH_UNSUPPORTED);
  binding.binding = a_click;
  EXPECT_EQ(xrSuggestInteractionProfileBindings(instance_, &suggested), XR_SUCCESS);

  auto get = tagged<XrActionStateGetInfo>(XR_TYPE_ACTION_STATE_GET_INFO);
  get.action = press;
  get.subactionPath = right;
  auto boolean = tagged<XrActionStateBoolean>(XR_TYPE_ACTION_STATE_BOOLEAN);
  EXPECT_EQ(xrGetActionStateBoolean(session_, &get, &boolean), XR_ERROR_ACTIONSET_NOT_ATTACHED);
  auto attach = tagged<XrSessionActionSetsAttachInfo>(XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO);
  attach.countActionSets = 1;
  attach.actionSets = &set;
  ASSERT_EQ(xrAttachSessionActionSets(session_, &attach), XR_SUCCESS);
  EXPECT_EQ(xrAttachSessionActionSets(session_, &attach), XR_ERROR_ACTIONSETS_ALREADY_ATTACHED);
  std::strcpy(ai.actionName, "late");
  XrAction late = XR_NULL_HANDLE;
  EXPECT_EQ(xrCreateAction(set, &ai, &late), XR_ERROR_ACTIONSETS_ALREADY_ATTACHED);
  EXPECT_EQ(xrSuggestInteractionProfileBindings(instance_, &suggested), XR_ERROR_ACTIONSETS_ALREADY_ATTACHED);

  EXPECT_EQ(xrGetActionStateBoolean(session_, &get, &boolean), XR_SUCCESS);
  EXPECT_EQ(boolean.isActive, XR_FALSE) << "no sync yet";
  auto as_float = tagged<XrActionStateFloat>(XR_TYPE_ACTION_STATE_FLOAT);
  EXPECT_EQ(xrGetActionStateFloat(session_, &get, &as_float), XR_ERROR_ACTION_TYPE_MISMATCH);
  get.subactionPath = left;
  EXPECT_EQ(xrGetActionStateBoolean(session_, &get, &boolean), XR_ERROR_PATH_UNSUPPORTED);
  auto space = tagged<XrActionSpaceCreateInfo>(XR_TYPE_ACTION_SPACE_CREATE_INFO);
  space.action = press;
  space.poseInActionSpace.orientation.w = 1.0f;
  XrSpace s = XR_NULL_HANDLE;
  EXPECT_EQ(xrCreateActionSpace(session_, &space, &s), XR_ERROR_ACTION_TYPE_MISMATCH);
  // Not focused yet (no frame has been submitted): the sync says so.
  XrActiveActionSet active{set, XR_NULL_PATH};
  auto sync = tagged<XrActionsSyncInfo>(XR_TYPE_ACTIONS_SYNC_INFO);
  sync.countActiveActionSets = 1;
  sync.activeActionSets = &active;
  EXPECT_EQ(xrSyncActions(session_, &sync), XR_SESSION_NOT_FOCUSED);
  EXPECT_EQ(violations(), 11);  // with the one in SetUp
  xrDestroyActionSet(set);
}

// Every OpenXR 1.0 core function (the 55 entry points of openxr.h 1.0.20
// without an extension suffix), asked of the runtime itself rather than of
// the loader, whose trampolines exist whether or not the runtime has the
// function: a null pointer there is a crash in an application.
TEST(RuntimeDispatch, EveryCoreFunctionHasAnEntryPoint) {
  void* lib = dlopen(CURVLAB_TEST_XR_RUNTIME_LIBRARY, RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(lib, nullptr) << dlerror();
  auto negotiate = reinterpret_cast<PFN_xrNegotiateLoaderRuntimeInterface>(
      dlsym(lib, "xrNegotiateLoaderRuntimeInterface"));
  ASSERT_NE(negotiate, nullptr);
  XrNegotiateLoaderInfo loader{XR_LOADER_INTERFACE_STRUCT_LOADER_INFO, 1, sizeof(XrNegotiateLoaderInfo), 1, 1,
                               XR_MAKE_VERSION(1, 0, 0), XR_CURRENT_API_VERSION};
  XrNegotiateRuntimeRequest request{XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST, 1, sizeof(XrNegotiateRuntimeRequest),
                                    0, 0, nullptr};
  ASSERT_EQ(negotiate(&loader, &request), XR_SUCCESS);
  const PFN_xrGetInstanceProcAddr gipa = request.getInstanceProcAddr;
  PFN_xrCreateInstance create = nullptr;
  ASSERT_EQ(gipa(XR_NULL_HANDLE, "xrCreateInstance", reinterpret_cast<PFN_xrVoidFunction*>(&create)), XR_SUCCESS);
  auto info = tagged<XrInstanceCreateInfo>(XR_TYPE_INSTANCE_CREATE_INFO);
  std::strcpy(info.applicationInfo.applicationName, "dispatch");
  info.applicationInfo.apiVersion = XR_MAKE_VERSION(1, 0, 0);
  XrInstance instance = XR_NULL_HANDLE;
  ASSERT_EQ(create(&info, &instance), XR_SUCCESS);
  const std::vector<std::string> core = {
      "xrGetInstanceProcAddr", "xrEnumerateApiLayerProperties", "xrEnumerateInstanceExtensionProperties",
      "xrCreateInstance", "xrDestroyInstance", "xrGetInstanceProperties", "xrPollEvent", "xrResultToString",
      "xrStructureTypeToString", "xrGetSystem", "xrGetSystemProperties", "xrEnumerateEnvironmentBlendModes",
      "xrCreateSession", "xrDestroySession", "xrEnumerateReferenceSpaces", "xrCreateReferenceSpace",
      "xrGetReferenceSpaceBoundsRect", "xrCreateActionSpace", "xrLocateSpace", "xrDestroySpace",
      "xrEnumerateViewConfigurations", "xrGetViewConfigurationProperties", "xrEnumerateViewConfigurationViews",
      "xrEnumerateSwapchainFormats", "xrCreateSwapchain", "xrDestroySwapchain", "xrEnumerateSwapchainImages",
      "xrAcquireSwapchainImage", "xrWaitSwapchainImage", "xrReleaseSwapchainImage", "xrBeginSession",
      "xrEndSession", "xrRequestExitSession", "xrWaitFrame", "xrBeginFrame", "xrEndFrame", "xrLocateViews",
      "xrStringToPath", "xrPathToString", "xrCreateActionSet", "xrDestroyActionSet", "xrCreateAction",
      "xrDestroyAction", "xrSuggestInteractionProfileBindings", "xrAttachSessionActionSets",
      "xrGetCurrentInteractionProfile", "xrGetActionStateBoolean", "xrGetActionStateFloat",
      "xrGetActionStateVector2f", "xrGetActionStatePose", "xrSyncActions", "xrEnumerateBoundSourcesForAction",
      "xrGetInputSourceLocalizedName", "xrApplyHapticFeedback", "xrStopHapticFeedback"};
  EXPECT_EQ(core.size(), 55u);
  for (const std::string& name : core) {
    PFN_xrVoidFunction fn = nullptr;
    EXPECT_EQ(gipa(instance, name.c_str(), &fn), XR_SUCCESS) << name;
    EXPECT_NE(fn, nullptr) << name;
  }
  PFN_xrVoidFunction none = nullptr;
  EXPECT_EQ(gipa(instance, "xrNoSuchFunction", &none), XR_ERROR_FUNCTION_UNSUPPORTED);
  EXPECT_EQ(none, nullptr);
  PFN_xrDestroyInstance destroy = nullptr;
  ASSERT_EQ(gipa(instance, "xrDestroyInstance", reinterpret_cast<PFN_xrVoidFunction*>(&destroy)), XR_SUCCESS);
  EXPECT_EQ(destroy(instance), XR_SUCCESS);
  dlclose(lib);
}

TEST_F(RuntimeRules, EnumerationsAndSpaces) {
  std::uint32_t n = 0;
  std::array<XrViewConfigurationType, 2> configs{};
  ASSERT_EQ(xrEnumerateViewConfigurations(instance_, system_, 0, &n, nullptr), XR_SUCCESS);
  ASSERT_EQ(n, 1u);
  ASSERT_EQ(xrEnumerateViewConfigurations(instance_, system_, 2, &n, configs.data()), XR_SUCCESS);
  EXPECT_EQ(configs[0], XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO);
  auto props = tagged<XrViewConfigurationProperties>(XR_TYPE_VIEW_CONFIGURATION_PROPERTIES);
  EXPECT_EQ(xrGetViewConfigurationProperties(instance_, system_, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_MONO, &props),
            XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED);
  ASSERT_EQ(xrGetViewConfigurationProperties(instance_, system_, configs[0], &props), XR_SUCCESS);
  EXPECT_EQ(props.viewConfigurationType, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO);
  XrEnvironmentBlendMode mode = XR_ENVIRONMENT_BLEND_MODE_MAX_ENUM;
  ASSERT_EQ(xrEnumerateEnvironmentBlendModes(instance_, system_, configs[0], 1, &n, &mode), XR_SUCCESS);
  EXPECT_EQ(mode, XR_ENVIRONMENT_BLEND_MODE_OPAQUE);
  // The two-call idiom: too small a capacity is refused, with the count.
  std::array<XrReferenceSpaceType, 3> spaces{};
  EXPECT_EQ(xrEnumerateReferenceSpaces(session_, 2, &n, spaces.data()), XR_ERROR_SIZE_INSUFFICIENT);
  EXPECT_EQ(n, 3u);
  ASSERT_EQ(xrEnumerateReferenceSpaces(session_, 3, &n, spaces.data()), XR_SUCCESS);
  EXPECT_EQ(spaces[2], XR_REFERENCE_SPACE_TYPE_STAGE);
  XrExtent2Df bounds{};
  ASSERT_EQ(xrGetReferenceSpaceBoundsRect(session_, XR_REFERENCE_SPACE_TYPE_STAGE, &bounds), XR_SUCCESS);
  EXPECT_GT(bounds.width, 1.0f);
  EXPECT_EQ(xrGetReferenceSpaceBoundsRect(session_, XR_REFERENCE_SPACE_TYPE_LOCAL, &bounds),
            XR_SPACE_BOUNDS_UNAVAILABLE);
  char text[XR_MAX_PATH_LENGTH];
  XrPath path = XR_NULL_PATH;
  ASSERT_EQ(xrStringToPath(instance_, "/user/hand/left", &path), XR_SUCCESS);
  EXPECT_EQ(xrPathToString(instance_, path, 4, &n, text), XR_ERROR_SIZE_INSUFFICIENT);
  EXPECT_EQ(n, 16u) << "15 characters and the terminating null";
  EXPECT_EQ(violations(), 1);  // the one in SetUp
}

// Bindings for any OpenXR 1.0 profile; the profile in use and its sources
// by name.
TEST_F(RuntimeRules, ProfilesAndTheirSources) {
  const HandActions h = hand_actions();
  EXPECT_EQ(suggest("/interaction_profiles/htc/vive_controller",
                    {{h.grab, path("/user/hand/left/input/trigger")},
                     {h.pose, path("/user/hand/left/input/grip/pose")},
                     {h.buzz, path("/user/hand/left/output/haptic")}}),
            XR_SUCCESS);
  EXPECT_EQ(suggest("/interaction_profiles/acme/glove", {{h.grab, path("/user/hand/left/input/trigger/value")}}),
            XR_ERROR_PATH_UNSUPPORTED);
  ASSERT_EQ(suggest_touch(h), XR_SUCCESS);
  auto profile = tagged<XrInteractionProfileState>(XR_TYPE_INTERACTION_PROFILE_STATE);
  EXPECT_EQ(xrGetCurrentInteractionProfile(session_, h.hands[0], &profile), XR_ERROR_ACTIONSET_NOT_ATTACHED);
  attach(h.set);
  // IDLE, READY, then the controllers' profile.
  XrStructureType last = XR_TYPE_UNKNOWN;
  for (auto e = tagged<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER); xrPollEvent(instance_, &e) == XR_SUCCESS;
       e = tagged<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER))
    last = e.type;
  EXPECT_EQ(last, XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED);
  ASSERT_EQ(xrGetCurrentInteractionProfile(session_, h.hands[1], &profile), XR_SUCCESS);
  EXPECT_EQ(profile.interactionProfile, path("/interaction_profiles/oculus/touch_controller"));
  ASSERT_EQ(xrGetCurrentInteractionProfile(session_, path("/user/head"), &profile), XR_SUCCESS);
  EXPECT_EQ(profile.interactionProfile, XR_NULL_PATH);
  EXPECT_EQ(xrGetCurrentInteractionProfile(session_, path("/user/hand/left/input"), &profile),
            XR_ERROR_PATH_UNSUPPORTED);

  auto bound = tagged<XrBoundSourcesForActionEnumerateInfo>(XR_TYPE_BOUND_SOURCES_FOR_ACTION_ENUMERATE_INFO);
  bound.action = h.grab;
  std::array<XrPath, 2> sources{};
  std::uint32_t n = 0;
  ASSERT_EQ(xrEnumerateBoundSourcesForAction(session_, &bound, 2, &n, sources.data()), XR_SUCCESS);
  ASSERT_EQ(n, 2u);
  EXPECT_EQ(sources[0], path("/user/hand/left/input/squeeze/value"));
  auto name_info = tagged<XrInputSourceLocalizedNameGetInfo>(XR_TYPE_INPUT_SOURCE_LOCALIZED_NAME_GET_INFO);
  name_info.sourcePath = sources[0];
  name_info.whichComponents = XR_INPUT_SOURCE_LOCALIZED_NAME_USER_PATH_BIT |
                              XR_INPUT_SOURCE_LOCALIZED_NAME_INTERACTION_PROFILE_BIT |
                              XR_INPUT_SOURCE_LOCALIZED_NAME_COMPONENT_BIT;
  ASSERT_EQ(xrGetInputSourceLocalizedName(session_, &name_info, 0, &n, nullptr), XR_SUCCESS);
  std::string name(n, '\0');
  ASSERT_EQ(xrGetInputSourceLocalizedName(session_, &name_info, n, &n, name.data()), XR_SUCCESS);
  EXPECT_STREQ(name.c_str(), "Left Hand Oculus Touch Controller Squeeze Value");
  EXPECT_EQ(violations(), 4);  // with the one in SetUp
  xrDestroyActionSet(h.set);
}

// Pose states and haptics follow input focus and action types; a destroyed
// action is an invalid handle.
TEST_F(RuntimeRules, PosesHapticsAndDestroyedActions) {
  const HandActions h = hand_actions();
  ASSERT_EQ(suggest_touch(h), XR_SUCCESS);
  attach(h.set);
  // Not focused yet (no frame submitted): inactive poses, haptics ignored.
  auto get = tagged<XrActionStateGetInfo>(XR_TYPE_ACTION_STATE_GET_INFO);
  get.action = h.pose;
  auto pose_state = tagged<XrActionStatePose>(XR_TYPE_ACTION_STATE_POSE);
  ASSERT_EQ(xrGetActionStatePose(session_, &get, &pose_state), XR_SUCCESS);
  EXPECT_EQ(pose_state.isActive, XR_FALSE);
  auto haptic = tagged<XrHapticActionInfo>(XR_TYPE_HAPTIC_ACTION_INFO);
  haptic.action = h.buzz;
  haptic.subactionPath = h.hands[1];
  auto vibration = tagged<XrHapticVibration>(XR_TYPE_HAPTIC_VIBRATION);
  vibration.duration = XR_MIN_HAPTIC_DURATION;
  vibration.amplitude = 0.5f;
  const auto* feedback = reinterpret_cast<const XrHapticBaseHeader*>(&vibration);
  EXPECT_EQ(xrApplyHapticFeedback(session_, &haptic, feedback), XR_SESSION_NOT_FOCUSED);
  haptic.action = h.grab;
  EXPECT_EQ(xrApplyHapticFeedback(session_, &haptic, feedback), XR_ERROR_ACTION_TYPE_MISMATCH);
  EXPECT_EQ(xrStopHapticFeedback(session_, &haptic), XR_ERROR_ACTION_TYPE_MISMATCH);

  ASSERT_EQ(xrDestroyAction(h.grab), XR_SUCCESS);
  get.action = h.grab;
  auto as_float = tagged<XrActionStateFloat>(XR_TYPE_ACTION_STATE_FLOAT);
  EXPECT_EQ(xrGetActionStateFloat(session_, &get, &as_float), XR_ERROR_HANDLE_INVALID);
  EXPECT_EQ(violations(), 4);  // with the one in SetUp
  xrDestroyActionSet(h.set);
}
}  // namespace
