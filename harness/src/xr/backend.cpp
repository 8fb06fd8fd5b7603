// The OpenXR backend (xr/backend.hpp). The order of the calls follows the
// OpenXR specification's lifecycle: instance → system → graphics
// requirements → Vulkan instance and device made by the runtime
// (XR_KHR_vulkan_enable2) → session → reference spaces and action spaces →
// swapchains; then per frame xrWaitFrame → xrBeginFrame → locate views and
// devices at the predicted display time → render → xrEndFrame.
#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/xr/backend.hpp"

#include "curvlab/harness/xr/actions.hpp"
#include "curvlab/harness/xr/gaze.hpp"
#include "curvlab/harness/xr/instance.hpp"
#include "curvlab/harness/xr/session_state.hpp"
#include "curvlab/harness/xr/stereo.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/gpu.hpp"
#include "curvlab/renderer/renderer.hpp"
#include "curvlab/renderer/swapchain.hpp"

#include <time.h>
#include <vulkan/vulkan.h>
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#ifdef _WIN32
#include <windows.h>
#define XR_USE_PLATFORM_WIN32
#endif
#include <openxr/openxr_platform.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <deque>
#include <iostream>
#include <limits>
#include <thread>
#include <utility>

namespace curvlab::xr {

using harness::Done;
using harness::Error;
using harness::Result;
using harness::io::DeviceFailure;
using harness::io::DisplayInfo;
using harness::io::Signal;
using harness::io::FrameTiming;
using harness::io::InputEvent;
using harness::io::InteractiveDisplay;
using harness::io::Overlay;

namespace {

constexpr XrViewConfigurationType kViewConfig = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
constexpr XrPosef kIdentityPose{{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
// Trigger hysteresis: a press above 0.75, a release below 0.25.
constexpr float kTriggerPress = 0.75f;
constexpr float kTriggerRelease = 0.25f;

// Owns one OpenXR child handle. Move-only; destroyed by the destructor.
template <class H, XrResult (*Destroy)(H)>
class Handle {
 public:
  Handle() = default;
  Handle(Handle&& o) noexcept : h_(std::exchange(o.h_, XR_NULL_HANDLE)) {}
  Handle& operator=(Handle&& o) noexcept {
    if (this != &o) {
      reset();
      h_ = std::exchange(o.h_, XR_NULL_HANDLE);
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }
  void reset() noexcept {
    if (h_ != XR_NULL_HANDLE) (void)Destroy(h_);
    h_ = XR_NULL_HANDLE;
  }
  [[nodiscard]] H get() const { return h_; }
  H* out() {
    reset();
    return &h_;
  }

 private:
  H h_ = XR_NULL_HANDLE;
};

using SessionHandle = Handle<XrSession, xrDestroySession>;
using SpaceHandle = Handle<XrSpace, xrDestroySpace>;
using SwapchainHandle = Handle<XrSwapchain, xrDestroySwapchain>;

// A factory failure (kind device or api, instance.hpp).
Error error(XrResult r, const char* call) { return failure_of(r, call); }

#ifdef _WIN32
// A QueryPerformanceCounter reading in nanoseconds, without overflow.
std::int64_t counter_ns(std::int64_t counter) {
  static const std::int64_t frequency = [] {
    LARGE_INTEGER f;
    QueryPerformanceFrequency(&f);
    return static_cast<std::int64_t>(f.QuadPart);
  }();
  return counter / frequency * 1'000'000'000 + counter % frequency * 1'000'000'000 / frequency;
}

// On Windows the performance counter, the clock
// XR_KHR_win32_convert_performance_counter_time converts to.
std::int64_t monotonic_now_ns() {
  LARGE_INTEGER c;
  QueryPerformanceCounter(&c);
  return counter_ns(c.QuadPart);
}
#else
std::int64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}
#endif

bool located(XrSpaceLocationFlags flags) {
  // Valid and tracked: an inferred (untracked) pose counts as lost tracking,
  // which is data (DESIGN.md §3), not a pose to show.
  constexpr XrSpaceLocationFlags want =
      XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT |
      XR_SPACE_LOCATION_POSITION_TRACKED_BIT | XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT;
  return (flags & want) == want;
}

// The orientation alone valid and tracked, as a 3-DoF device or one that
// lost its position reports it.
bool orientation_located(XrSpaceLocationFlags flags) {
  constexpr XrSpaceLocationFlags want = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT;
  return (flags & want) == want;
}

// Valid, perhaps inferred: a pose the runtime says can be used. The head's
// is used so; whether its tracking is good enough for a trial is the
// protocol's [tracking] head_requires (a headset without positional
// tracking, or Monado's simulated one, infers the position).
bool usable(XrSpaceLocationFlags flags) {
  constexpr XrSpaceLocationFlags want = XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  return (flags & want) == want;
}

// The flags by their names in the specification, for messages.
std::string location_flags_text(XrSpaceLocationFlags flags) {
  std::string out;
  for (const auto& [bit, name] : {std::pair{XR_SPACE_LOCATION_ORIENTATION_VALID_BIT, "ORIENTATION_VALID"},
                                  std::pair{XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT, "ORIENTATION_TRACKED"},
                                  std::pair{XR_SPACE_LOCATION_POSITION_VALID_BIT, "POSITION_VALID"},
                                  std::pair{XR_SPACE_LOCATION_POSITION_TRACKED_BIT, "POSITION_TRACKED"}}) {
    out += out.empty() ? "" : " | ";
    out += (flags & bit) != 0 ? name : std::string("no ") + name;
  }
  return out;
}

std::string vk_result(VkResult r) { return vk::to_string(static_cast<vk::Result>(r)); }

// The instance extensions curvlab asks for besides XR_KHR_vulkan_enable2,
// where the runtime offers them.
struct OptionalExtensions {
  bool timespec = false;  // XR_KHR_convert_timespec_time
  // XR_KHR_win32_convert_performance_counter_time, what Windows runtimes
  // (SteamVR, Meta, WMR) offer instead; used where timespec is not offered.
  bool win32_time = false;
  // XR_FB_display_refresh_rate: the display's refresh rate before the first
  // frame, for the session's provenance (Meta, Pico and Monado offer it).
  bool refresh = false;
  GazeExtensions gaze;  // eye tracking (xr/gaze.hpp)

  [[nodiscard]] std::vector<std::string> names() const {
    std::vector<std::string> out;
    if (timespec) out.emplace_back(XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME);
#ifdef _WIN32
    if (win32_time && !timespec) out.emplace_back(XR_KHR_WIN32_CONVERT_PERFORMANCE_COUNTER_TIME_EXTENSION_NAME);
#endif
    if (refresh) out.emplace_back(XR_FB_DISPLAY_REFRESH_RATE_EXTENSION_NAME);
    for (auto& n : gaze.names()) out.push_back(std::move(n));
    return out;
  }
};

// The extension list comes from the runtime: without one, this is where
// XR_ERROR_RUNTIME_UNAVAILABLE shows, before anything is created.
Result<OptionalExtensions> offered_extensions() {
  auto offered = available_extensions();
  if (!offered) return offered.error();
  const auto& names = offered.value();
  auto has = [&names](const char* n) { return std::find(names.begin(), names.end(), n) != names.end(); };
  if (!has(XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME))
    return error(XR_ERROR_EXTENSION_NOT_PRESENT, "xrEnumerateInstanceExtensionProperties");
#ifdef _WIN32
  const bool win32_time = has(XR_KHR_WIN32_CONVERT_PERFORMANCE_COUNTER_TIME_EXTENSION_NAME);
#else
  const bool win32_time = false;
#endif
  return OptionalExtensions{.timespec = has(XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME),
                            .win32_time = win32_time,
                            .refresh = has(XR_FB_DISPLAY_REFRESH_RATE_EXTENSION_NAME),
                            .gaze = gaze_extensions_in(names)};
}

// XR_KHR_vulkan_enable2's functions, for one instance and system.
struct VulkanEnable2 {
  XrInstance instance = XR_NULL_HANDLE;
  XrSystemId system = XR_NULL_SYSTEM_ID;
  PFN_xrGetVulkanGraphicsRequirements2KHR requirements = nullptr;
  PFN_xrCreateVulkanInstanceKHR create_instance = nullptr;
  PFN_xrGetVulkanGraphicsDevice2KHR physical_device = nullptr;
  PFN_xrCreateVulkanDeviceKHR create_device = nullptr;
};

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
    if (XR_FAILED(r)) return error(r, name);
  return fns;
}

// Required before the session; curvlab needs Vulkan 1.3 (dynamic rendering).
Result<Done> check_vulkan_version(const VulkanEnable2& fns) {
  auto req = tagged<XrGraphicsRequirementsVulkan2KHR>(XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR);
  if (const XrResult r = fns.requirements(fns.instance, fns.system, &req); XR_FAILED(r))
    return error(r, "xrGetVulkanGraphicsRequirements2KHR");
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

// The hooks through which the runtime makes the Vulkan objects from the
// renderer's create-infos.
renderer::ContextEmbedding runtime_made_vulkan(const VulkanEnable2& fns) {
  renderer::ContextEmbedding runtime_made;
  runtime_made.hooks.create_instance = [fns](const VkInstanceCreateInfo& info)
      -> std::variant<VkInstance, renderer::RenderError> {
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
  runtime_made.hooks.pick_physical_device = [fns](VkInstance instance)
      -> std::variant<VkPhysicalDevice, renderer::RenderError> {
    auto gi = tagged<XrVulkanGraphicsDeviceGetInfoKHR>(XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR);
    gi.systemId = fns.system;
    gi.vulkanInstance = instance;
    VkPhysicalDevice physical = VK_NULL_HANDLE;
    if (const XrResult r = fns.physical_device(fns.instance, &gi, &physical); XR_FAILED(r))
      return runtime_failure(failure_of(r, "xrGetVulkanGraphicsDevice2KHR").message);
    return physical;
  };
  runtime_made.hooks.create_device = [fns](VkPhysicalDevice physical, const VkDeviceCreateInfo& info)
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
  return runtime_made;
}

// Two-call enumeration of the swapchain formats the runtime offers.
Result<std::vector<std::int64_t>> swapchain_formats(XrSession session) {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateSwapchainFormats(session, 0, &count, nullptr); XR_FAILED(r))
    return error(r, "xrEnumerateSwapchainFormats");
  std::vector<std::int64_t> formats(count);
  if (const XrResult r = xrEnumerateSwapchainFormats(session, count, &count, formats.data()); XR_FAILED(r))
    return error(r, "xrEnumerateSwapchainFormats");
  return formats;
}

// The stereo view configuration's two views (the recommended image sizes).
Result<std::vector<XrViewConfigurationView>> stereo_views(XrInstance xr, XrSystemId sys) {
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateViewConfigurationViews(xr, sys, kViewConfig, 0, &count, nullptr);
      XR_FAILED(r))
    return error(r, "xrEnumerateViewConfigurationViews");
  std::vector<XrViewConfigurationView> config(count, tagged<XrViewConfigurationView>(XR_TYPE_VIEW_CONFIGURATION_VIEW));
  if (const XrResult r = xrEnumerateViewConfigurationViews(xr, sys, kViewConfig, count, &count, config.data());
      XR_FAILED(r))
    return error(r, "xrEnumerateViewConfigurationViews");
  if (count != 2)
    return Error{Error::Kind::device, "the headset's stereo view configuration has " + std::to_string(count) +
                                          " views; curvlab needs 2"};
  return config;
}

// The operator window's copies of the submitted swapchain images (FrameMirror
// in io/display.hpp). The frame thread records, in a command buffer of
// its own submitted right after the frame's (same queue, so after it), a
// copy of both eyes into a host-visible buffer; the operator's thread waits
// on the fence and reads the buffer. One copy in flight; `state_` hands the
// buffer and fence between the two threads (acquire/release): idle → requested
// (operator) → copying (frame thread) → idle (operator, after reading).
// A UNORM swapchain holds linear values (the compositor encodes them for the
// display): the copy is sRGB-encoded on reading, so the window shows what
// the headset does.
class XrMirror final : public harness::io::FrameMirror {
 public:
  XrMirror(const renderer::Context& ctx, vk::Extent2D eye, bool bgra, bool linear)
      : ctx_(ctx),
        eye_(eye),
        bgra_(bgra),
        encode_(encoding(linear)),
        pool_(ctx.device(), {.flags = vk::CommandPoolCreateFlagBits::eResetCommandBuffer,
                             .queueFamilyIndex = ctx.queue_family()}),
        fence_(ctx.device(), vk::FenceCreateInfo{}),
        staging_(renderer::Buffer::create(ctx, vk::DeviceSize{2} * eye.width * eye.height * 4,
                                          vk::BufferUsageFlagBits::eTransferDst)) {
    vk::raii::CommandBuffers cbs(ctx.device(), {.commandPool = *pool_,
                                                .level = vk::CommandBufferLevel::ePrimary,
                                                .commandBufferCount = 1});
    cb_ = std::move(cbs.front());
  }
  ~XrMirror() override {
    if (state_.load(std::memory_order_acquire) == kCopying)
      (void)ctx_.device().waitForFences(*fence_, VK_TRUE, 1'000'000'000);
  }

  void request() override {
    int idle = kIdle;
    state_.compare_exchange_strong(idle, kRequested, std::memory_order_acq_rel);
  }

  bool take(harness::io::MirrorImage& out) override {
    if (state_.load(std::memory_order_acquire) != kCopying) return false;
    if (ctx_.device().waitForFences(*fence_, VK_TRUE, 0) != vk::Result::eSuccess) return false;
    out.width = eye_.width * 2;
    out.height = eye_.height;
    out.rgba.resize(std::size_t{out.width} * out.height * 4);
    const auto* src = static_cast<const std::uint8_t*>(staging_.mapped);
    const std::size_t row = std::size_t{eye_.width} * 4;
    for (std::uint32_t y = 0; y < eye_.height; ++y)
      for (std::size_t e = 0; e < 2; ++e)
        std::memcpy(out.rgba.data() + (std::size_t{y} * out.width * 4) + e * row,
                    src + e * row * eye_.height + y * row, row);
    if (bgra_)
      for (std::size_t i = 0; i < out.rgba.size(); i += 4) std::swap(out.rgba[i], out.rgba[i + 2]);
    for (std::size_t i = 0; i < out.rgba.size(); ++i)
      if (i % 4 != 3) out.rgba[i] = encode_[out.rgba[i]];
    state_.store(kIdle, std::memory_order_release);
    return true;
  }

  // Frame thread, with both eyes' swapchain images still acquired and the
  // frame's own commands submitted: copies them when a copy was requested.
  void copy(const std::array<vk::Image, 2>& images) {
    if (state_.load(std::memory_order_acquire) != kRequested) return;
    ctx_.device().resetFences(*fence_);
    cb_.reset();
    cb_.begin({.flags = vk::CommandBufferUsageFlagBits::eOneTimeSubmit});
    for (std::size_t e = 0; e < 2; ++e) {
      constexpr auto color = vk::ImageAspectFlagBits::eColor;
      renderer::transition(cb_, images[e], color, vk::ImageLayout::eColorAttachmentOptimal,
                           vk::ImageLayout::eTransferSrcOptimal);
      const vk::BufferImageCopy region{.bufferOffset = vk::DeviceSize{e} * eye_.width * eye_.height * 4,
                                       .imageSubresource = {color, 0, 0, 1},
                                       .imageExtent = {eye_.width, eye_.height, 1}};
      cb_.copyImageToBuffer(images[e], vk::ImageLayout::eTransferSrcOptimal, *staging_.buffer, region);
      renderer::transition(cb_, images[e], color, vk::ImageLayout::eTransferSrcOptimal,
                           vk::ImageLayout::eColorAttachmentOptimal);
    }
    cb_.end();
    ctx_.submit(*cb_, *fence_);
    state_.store(kCopying, std::memory_order_release);
  }

 private:
  // The bytes shown for each byte read: sRGB-encoded (IEC 61966-2-1) for a
  // linear image, as they are otherwise.
  static std::array<std::uint8_t, 256> encoding(bool linear) {
    std::array<std::uint8_t, 256> lut{};
    for (int v = 0; v < 256; ++v) {
      const double l = v / 255.0;
      const double e = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
      lut[static_cast<std::size_t>(v)] = static_cast<std::uint8_t>(linear ? std::lround(e * 255.0) : v);
    }
    return lut;
  }

  static constexpr int kIdle = 0, kRequested = 1, kCopying = 2;
  const renderer::Context& ctx_;
  vk::Extent2D eye_;
  bool bgra_;
  std::array<std::uint8_t, 256> encode_;
  vk::raii::CommandPool pool_;
  vk::raii::CommandBuffer cb_{nullptr};
  vk::raii::Fence fence_;
  renderer::Buffer staging_;
  std::atomic<int> state_{kIdle};
};

}  // namespace

// Owns, in order of destruction: the eye target and renderer, the swapchains,
// spaces and session, the Vulkan context (instance and device made through
// the runtime), the action set, the OpenXR instance. Runs on one thread (the
// runner's frame loop); not thread-safe.
class XrBackend final : public InteractiveDisplay {
 public:
  static Result<std::unique_ptr<InteractiveDisplay>> create(const XrBackendOptions& options);
  // Ends a begun frame and the session as far as the runtime still answers;
  // never throws (a lost session or device included).
  ~XrBackend() override;

  [[nodiscard]] DisplayInfo info() const override;
  std::optional<FrameTiming> begin_frame() override;
  geometry::LabFrame poses(const FrameTiming& frame) override;
  [[nodiscard]] harness::io::HeadTracking head_tracking() const override;
  [[nodiscard]] std::string describe_head_tracking() const override;
  [[nodiscard]] std::optional<harness::io::Gaze> gaze() const override { return gaze_; }
  // Session-state events: pause, resume, quit.
  Signal poll_signal() override;
  // The controllers' buttons.
  Signal poll(std::vector<InputEvent>& out) override;
  [[nodiscard]] harness::io::Reach reach() const override { return controller_reach(); }
  renderer::StereoRig rig(const FrameTiming& frame, double ipd_m) override;
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const Overlay& overlay, bool draw) override;
  std::vector<std::string> save_frame(const std::string& stem) override;
  harness::io::FrameMirror* mirror() override { return mirror_.get(); }
  void take_reports(std::vector<harness::io::DisplayReport>& out) override {
    out.insert(out.end(), reports_.begin(), reports_.end());
    reports_.clear();
  }

 private:
  struct EyeSwapchain {
    SwapchainHandle handle;
    std::vector<XrSwapchainImageVulkan2KHR> images;
    std::uint32_t width = 0;
    std::uint32_t height = 0;
  };

  XrBackend(Instance instance, const XrBackendOptions& options)
      : options_(options), instance_(std::move(instance)) {}
  // Drains the event queue; false when the session must end.
  bool poll_events();
  void leave_session();
  std::int64_t monotonic_to_session();
  void on_state(SessionState next);
  // Marks the backend failed and throws DeviceFailure naming the call.
  [[noreturn]] void fail(XrResult r, const char* call);
  [[noreturn]] void fail(const renderer::VulkanFailure& f);
  // What a frame ends with: the projection layer just rendered into the
  // swapchains, the last one again (a frame the runner began but did not
  // draw: the image before it stays up instead of a black refresh), or none.
  enum class FrameLayer { fresh, held, none };
  // xrEndFrame; its result is left to the caller (the frame loop fails on
  // it, teardown ignores it).
  [[nodiscard]] XrResult end_frame(FrameLayer layer);
  // For a frame ended without drawing: the last layer where the runtime
  // shows this frame (shouldRender), none where it does not.
  [[nodiscard]] FrameLayer undrawn() const {
    return frame_state_.shouldRender == XR_TRUE ? FrameLayer::held : FrameLayer::none;
  }
  std::int64_t to_session_ns(XrTime t);
  // xrSyncActions for this frame (a failure other than a lost session is
  // logged; the states then read inactive).
  void sync_actions();
  void read_buttons(std::vector<InputEvent>& out);
  // Logs a failed action-state query once per call name (it repeats every
  // frame otherwise) and goes on: one unreadable button must not end a session.
  void report_once(XrResult r, const char* call);
  void mark_late(FrameTiming& timing);
  FrameTiming stopped_frame();
  // The runtime's events that are not session states.
  void on_events_lost(const XrEventDataEventsLost& e);
  void on_stage_change(const XrEventDataReferenceSpaceChangePending& e);
  void on_refresh_rate_changed(const XrEventDataDisplayRefreshRateChangedFB& e);
  // Asks the display for the protocol's refresh rate where it offers it
  // (XR_FB_display_refresh_rate); the rate it then runs at.
  void request_refresh_rate();
  // Switches to the STAGE space that keeps the lab frame once the frame's
  // display time has reached the runtime's change time.
  void follow_stage_change(XrTime t);
  // xrWaitSwapchainImage in bounded steps (a runtime's back-pressure), so a
  // compositor that holds an image is said and, past a limit, a failure.
  void wait_image(XrSwapchain swapchain);
  // The steps of create(), in the order of the OpenXR lifecycle; each keeps
  // what it made in the members.
  Result<Done> open(const OptionalExtensions& offered);
  Result<Done> make_context(const VulkanEnable2& vulkan);
  Result<Done> create_session(bool refresh_rate);
  Result<Done> make_spaces();
  Result<Done> make_swapchains();
  Result<Done> make_swapchain(EyeSwapchain& sc, const XrViewConfigurationView& view);
  Result<Done> make_renderer();

  XrBackendOptions options_;
  Instance instance_;
  XrSystemId system_ = XR_NULL_SYSTEM_ID;
  std::optional<ActionSet> actions_;
  std::unique_ptr<renderer::Context> context_;
  SessionHandle session_;
  SpaceHandle stage_;
  SpaceHandle view_;
  std::array<SpaceHandle, 2> grip_;  // left, right
  std::array<XrPath, 2> hand_paths_{XR_NULL_PATH, XR_NULL_PATH};
  // Destroyed before the spaces and the session it was started on.
  std::optional<EyeTracking> eyes_;
  std::array<EyeSwapchain, 2> swapchains_;
  std::int64_t swapchain_format_ = 0;
  std::unique_ptr<renderer::Renderer> renderer_;
  std::unique_ptr<renderer::ExternalImagesTarget> target_;
  std::unique_ptr<XrMirror> mirror_;

  SessionStateMachine state_;
  PFN_xrConvertTimeToTimespecTimeKHR to_timespec_ = nullptr;
#ifdef _WIN32
  PFN_xrConvertTimeToWin32PerformanceCounterKHR to_counter_ = nullptr;
#endif
  XrClockMap clock_map_;
  std::deque<Signal> signals_;
  bool failed_ = false;
  std::vector<std::string> reported_;
  double refresh_hz_ = 90.0;

  XrFrameState frame_state_ = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  bool frame_begun_ = false;
  bool leaving_ = false;  // leave_session asked the runtime to end the session
  std::int64_t offset_ns_ = 0;      // monotonic_to_session's estimate
  std::int64_t offset_at_ns_ = -1;  // when it was made (CLOCK_MONOTONIC); -1 none
  std::int64_t frame_index_ = 0;
  std::array<XrView, 2> views_{tagged<XrView>(XR_TYPE_VIEW), tagged<XrView>(XR_TYPE_VIEW)};
  // The views of the last layer submitted with a fresh image (the pose and
  // field of view its images were rendered for); nullopt before the first.
  std::optional<std::array<XrView, 2>> shown_views_;
  bool views_valid_ = false;
  LabPose head_;
  geometry::LabFrame lab_;
  std::optional<harness::io::Gaze> gaze_;  // located with lab_; nullopt without eye tracking
  XrSpaceLocationFlags head_flags_ = 0;  // the head's at the last locate
  std::array<bool, 2> trigger_down_{false, false};
  bool synced_ = false;  // xrSyncActions was called in this frame while FOCUSED
  // Per action of curvlab_action_set() and hand: active at the last read
  // (false after a focus loss, so the first read after it is a baseline).
  std::vector<std::array<bool, 2>> active_ = std::vector<std::array<bool, 2>>(curvlab_action_set().actions.size());
  XrTime focused_at_ = 0;  // when the session last became FOCUSED (the runtime's event time)
  XrTime last_display_ = 0;  // the previous frame's predicted display time
  std::vector<harness::io::DisplayReport> reports_;  // for the session's data, until taken
  // STAGE as curvlab uses it: the runtime's STAGE with an offset that keeps
  // the lab frame where it was before the runtime moved STAGE's origin
  // (identity until then); a moved space waits in stage_next_ for its change time.
  XrPosef stage_offset_ = kIdentityPose;
  SpaceHandle stage_next_;
  XrPosef stage_next_offset_ = kIdentityPose;
  XrTime stage_change_at_ = 0;
  // XR_FB_display_refresh_rate, where enabled.
  PFN_xrGetDisplayRefreshRateFB get_refresh_ = nullptr;
  PFN_xrEnumerateDisplayRefreshRatesFB enumerate_refresh_ = nullptr;
  PFN_xrRequestDisplayRefreshRateFB request_refresh_ = nullptr;
  float requested_hz_ = 0.0f;  // the rate curvlab asked for; its change event is expected (0: none)
  bool swapchain_wait_said_ = false;
  bool focus_wait_ = false;       // READY came, the first focus not yet: a pause held back
  std::int64_t frames_ended_ = 0;  // xrEndFrame calls
};

Result<std::unique_ptr<InteractiveDisplay>> XrBackend::create(const XrBackendOptions& options) {
  if (options.clock == nullptr)
    return Error{Error::Kind::usage, "the OpenXR backend needs the session clock (XrBackendOptions::clock)"};
  auto offered = offered_extensions();
  if (!offered) return offered.error();
  auto made = Instance::create(options.application_name, offered->names());
  if (!made) return made.error();
  std::unique_ptr<XrBackend> b(new XrBackend(std::move(made).value(), options));
  if (auto opened = b->open(offered.value()); !opened) return opened.error();
  return std::unique_ptr<InteractiveDisplay>(std::move(b));
}

Result<Done> XrBackend::open(const OptionalExtensions& offered) {
  const XrInstance xr = instance_.handle();
  if (offered.timespec && XR_FAILED(load(xr, "xrConvertTimeToTimespecTimeKHR", to_timespec_)))
    to_timespec_ = nullptr;
#ifdef _WIN32
  if (!offered.timespec && offered.win32_time &&
      XR_FAILED(load(xr, "xrConvertTimeToWin32PerformanceCounterKHR", to_counter_)))
    to_counter_ = nullptr;
#endif
  auto system = instance_.hmd_system();
  if (!system) return system.error();
  system_ = system.value();
  auto vulkan = load_vulkan_enable2(xr, system_);
  if (!vulkan) return vulkan.error();
  if (auto r = check_vulkan_version(vulkan.value()); !r) return r;
  // Before the session: the combined gaze's action set and binding must be
  // suggested before the attach.
  auto eyes = EyeTracking::create(instance_, system_, offered.gaze);
  if (!eyes) return eyes.error();
  eyes_.emplace(std::move(eyes).value());
  if (auto r = make_context(vulkan.value()); !r) return r;
  if (auto r = create_session(offered.refresh); !r) return r;
  if (auto r = make_spaces(); !r) return r;
  if (auto r = make_swapchains(); !r) return r;
  return make_renderer();
}

Result<Done> XrBackend::make_context(const VulkanEnable2& vulkan) {
  auto ctx = harness::from_renderer(renderer::Context::create(renderer::ContextOptions{}, runtime_made_vulkan(vulkan)),
                           "cannot render for the headset: ");
  if (!ctx) return ctx.error();
  context_ = std::make_unique<renderer::Context>(std::move(ctx).value());
  return Done{};
}

Result<Done> XrBackend::create_session(bool refresh_rate) {
  // The action set exists before the session so it can be attached to it.
  auto set = ActionSet::create(instance_, curvlab_action_set());
  if (!set) return set.error();
  actions_.emplace(std::move(set).value());

  const renderer::Context& c = *context_;
  auto binding = tagged<XrGraphicsBindingVulkan2KHR>(XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR);
  binding.instance = static_cast<VkInstance>(*c.instance());
  binding.physicalDevice = static_cast<VkPhysicalDevice>(*c.physical());
  binding.device = static_cast<VkDevice>(*c.device());
  binding.queueFamilyIndex = c.queue_family();
  binding.queueIndex = 0;
  auto session_info = tagged<XrSessionCreateInfo>(XR_TYPE_SESSION_CREATE_INFO);
  session_info.next = &binding;
  session_info.systemId = system_;
  if (const XrResult r = xrCreateSession(instance_.handle(), &session_info, session_.out()); XR_FAILED(r))
    return error(r, "xrCreateSession");
  const XrInstance xr = instance_.handle();
  if (refresh_rate && XR_SUCCEEDED(load(xr, "xrGetDisplayRefreshRateFB", get_refresh_)) &&
      XR_SUCCEEDED(load(xr, "xrEnumerateDisplayRefreshRatesFB", enumerate_refresh_)) &&
      XR_SUCCEEDED(load(xr, "xrRequestDisplayRefreshRateFB", request_refresh_))) {
    float hz = 0.0f;
    if (XR_SUCCEEDED(get_refresh_(session_.get(), &hz)) && hz > 0.0f) refresh_hz_ = static_cast<double>(hz);
    request_refresh_rate();
  } else {
    get_refresh_ = nullptr;
  }
  return Done{};
}

// A lab fixes the display rate for its timing: the protocol's rate where the
// headset offers it; otherwise the headset's own, said.
void XrBackend::request_refresh_rate() {
  if (!options_.refresh_hz || request_refresh_ == nullptr) return;
  const double want = *options_.refresh_hz;
  if (std::abs(refresh_hz_ - want) < 0.5) return;
  std::uint32_t n = 0;
  std::vector<float> rates;
  if (XR_SUCCEEDED(enumerate_refresh_(session_.get(), 0, &n, nullptr))) {
    rates.resize(n);
    if (XR_FAILED(enumerate_refresh_(session_.get(), n, &n, rates.data()))) rates.clear();
  }
  const auto offered = std::find_if(rates.begin(), rates.end(),
                                    [want](float r) { return std::abs(static_cast<double>(r) - want) < 0.5; });
  if (offered == rates.end()) {
    std::string list;
    for (const float r : rates) list += (list.empty() ? "" : ", ") + std::to_string(std::lround(r));
    std::cerr << "curvlab: xr: the headset does not offer the protocol's " << want << " Hz (it offers " << list
              << " Hz); frames run at its " << refresh_hz_ << " Hz\n";
    return;
  }
  if (const XrResult r = request_refresh_(session_.get(), *offered); XR_FAILED(r)) {
    std::cerr << "curvlab: xr: " << failure_of(r, "xrRequestDisplayRefreshRateFB").message << '\n';
    return;
  }
  float now = 0.0f;
  if (XR_FAILED(get_refresh_(session_.get(), &now)) || now <= 0.0f) now = *offered;
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::refresh_rate;
  report.from_hz = refresh_hz_;
  report.to_hz = now;
  report.requested = true;
  reports_.push_back(report);
  refresh_hz_ = now;
  requested_hz_ = *offered;
}

// The STAGE and VIEW reference spaces, and a grip space per hand once the
// action set is attached.
Result<Done> XrBackend::make_spaces() {
  const XrSession session = session_.get();
  auto space_info = tagged<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
  space_info.poseInReferenceSpace = kIdentityPose;
  space_info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
  if (const XrResult r = xrCreateReferenceSpace(session, &space_info, stage_.out()); XR_FAILED(r))
    return Error{Error::Kind::device,
                 failure_of(r, "xrCreateReferenceSpace").message +
                     " (STAGE space: set up the play area / room boundary in the runtime, so "
                     "that the floor and the table are where curvlab's lab frame says)"};
  space_info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  if (const XrResult r = xrCreateReferenceSpace(session, &space_info, view_.out()); XR_FAILED(r))
    return error(r, "xrCreateReferenceSpace");

  // Attached once, all together: curvlab's and the eye gaze's.
  std::vector<XrActionSet> action_sets{actions_->handle()};
  if (eyes_->action_set() != XR_NULL_HANDLE) action_sets.push_back(eyes_->action_set());
  auto attach = tagged<XrSessionActionSetsAttachInfo>(XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO);
  attach.countActionSets = static_cast<std::uint32_t>(action_sets.size());
  attach.actionSets = action_sets.data();
  if (const XrResult r = xrAttachSessionActionSets(session, &attach); XR_FAILED(r))
    return error(r, "xrAttachSessionActionSets");
  if (auto r = eyes_->start(session); !r) return r;
  for (std::size_t i = 0; i < 2; ++i) {
    if (const XrResult r = xrStringToPath(instance_.handle(), i == 0 ? kLeftHand : kRightHand, &hand_paths_[i]);
        XR_FAILED(r))
      return error(r, "xrStringToPath");
    auto info = tagged<XrActionSpaceCreateInfo>(XR_TYPE_ACTION_SPACE_CREATE_INFO);
    info.action = actions_->action("grip_pose");
    info.subactionPath = hand_paths_[i];
    info.poseInActionSpace = kIdentityPose;
    if (const XrResult r = xrCreateActionSpace(session, &info, grip_[i].out()); XR_FAILED(r))
      return error(r, "xrCreateActionSpace");
  }
  return Done{};
}

// One swapchain per eye at the runtime's recommended size.
Result<Done> XrBackend::make_swapchains() {
  auto views = stereo_views(instance_.handle(), system_);
  if (!views) return views.error();
  auto formats = swapchain_formats(session_.get());
  if (!formats) return formats.error();
  const auto format = choose_swapchain_format(formats.value());
  if (!format)
    return Error{Error::Kind::device, "the OpenXR runtime offers no 8-bit RGBA or BGRA swapchain format "
                                      "(xrEnumerateSwapchainFormats); curvlab cannot show its images"};
  swapchain_format_ = *format;
  for (std::size_t i = 0; i < 2; ++i)
    if (auto r = make_swapchain(swapchains_[i], views.value()[i]); !r) return r;
  return Done{};
}

Result<Done> XrBackend::make_swapchain(EyeSwapchain& sc, const XrViewConfigurationView& view) {
  sc.width = view.recommendedImageRectWidth;
  sc.height = view.recommendedImageRectHeight;
  auto info = tagged<XrSwapchainCreateInfo>(XR_TYPE_SWAPCHAIN_CREATE_INFO);
  // TRANSFER_SRC: the operator window's copies (XrMirror).
  info.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT |
                    XR_SWAPCHAIN_USAGE_TRANSFER_SRC_BIT;
  info.format = swapchain_format_;
  info.sampleCount = 1;
  info.width = sc.width;
  info.height = sc.height;
  info.faceCount = 1;
  info.arraySize = 1;
  info.mipCount = 1;
  if (const XrResult r = xrCreateSwapchain(session_.get(), &info, sc.handle.out()); XR_FAILED(r))
    return error(r, "xrCreateSwapchain");
  std::uint32_t count = 0;
  if (const XrResult r = xrEnumerateSwapchainImages(sc.handle.get(), 0, &count, nullptr); XR_FAILED(r))
    return error(r, "xrEnumerateSwapchainImages");
  sc.images.assign(count, tagged<XrSwapchainImageVulkan2KHR>(XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR));
  if (const XrResult r = xrEnumerateSwapchainImages(
          sc.handle.get(), count, &count,
          reinterpret_cast<XrSwapchainImageBaseHeader*>(sc.images.data()));
      XR_FAILED(r))
    return error(r, "xrEnumerateSwapchainImages");
  return Done{};
}

// The renderer, the target that draws into the swapchain images and, when
// asked for, the operator window's mirror.
Result<Done> XrBackend::make_renderer() {
  const renderer::Context& c = *context_;
  try {
    renderer_ = std::make_unique<renderer::Renderer>(c, renderer::RendererOptions{.msaa = options_.msaa});
  } catch (const renderer::VulkanFailure& f) {
    return Error{Error::Kind::api, std::string("cannot render for the headset: ") + f.what()};
  } catch (const vk::SystemError& e) {
    return Error{Error::Kind::api, "cannot render for the headset: " + renderer::vk_call_name(e.what()) +
                                       ": " + renderer::vk_result_name(e.code().value())};
  }
  target_ = std::make_unique<renderer::ExternalImagesTarget>(c);
  if (options_.mirror) {
    const auto format = static_cast<vk::Format>(swapchain_format_);
    const bool bgra = format == vk::Format::eB8G8R8A8Srgb || format == vk::Format::eB8G8R8A8Unorm;
    const bool linear = format == vk::Format::eR8G8B8A8Unorm || format == vk::Format::eB8G8R8A8Unorm;
    mirror_ = std::make_unique<XrMirror>(c, vk::Extent2D{swapchains_[0].width, swapchains_[0].height}, bgra, linear);
  }
  return Done{};
}

XrBackend::~XrBackend() {
  // A frame the runner began but never submitted must still end; after a
  // failure the runtime may answer with errors, which nothing can act on
  // here (the failure was reported where it happened).
  try {
    if (frame_begun_) (void)end_frame(undrawn());
    leave_session();
  } catch (...) {
    // poll_events() throws for a runtime that fails while we leave: leave anyway.
  }
  if (renderer_) renderer_->wait_idle_noexcept();
}

// The runner is done with a session the runtime still runs: ask the runtime
// to end it (xrRequestExitSession), keep frames flowing without layers while
// it steps down to STOPPING, and end it there, so the runtime sees an
// orderly exit rather than a running session destroyed. Bounded to 2 s.
void XrBackend::leave_session() {
  if (failed_ || !state_.session_running()) return;
  if (const XrResult r = xrRequestExitSession(session_.get()); XR_FAILED(r)) {
    std::cerr << "curvlab: xr: " << failure_of(r, "xrRequestExitSession").message << '\n';
    return;
  }
  leaving_ = true;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < deadline) {
    if (!poll_events() || !state_.session_running()) break;
    auto wait_info = tagged<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
    frame_state_ = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
    if (XR_FAILED(xrWaitFrame(session_.get(), &wait_info, &frame_state_))) break;
    auto begin_info = tagged<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
    if (XR_FAILED(xrBeginFrame(session_.get(), &begin_info))) break;
    frame_begun_ = true;
    if (XR_FAILED(end_frame(undrawn()))) break;
  }
}

DisplayInfo XrBackend::info() const {
  // Once frames run, the runtime's frame period; before, the display's
  // reported rate (XR_FB_display_refresh_rate) or 90 Hz, the common rate.
  const double period = static_cast<double>(frame_state_.predictedDisplayPeriod);
  return {"xr", context_->device_name(), context_->driver_info(), period > 0.0 ? 1e9 / period : refresh_hz_,
          swapchains_[0].width, swapchains_[0].height, renderer_ ? renderer_->msaa() : 0};
}

void XrBackend::fail(XrResult r, const char* call) {
  failed_ = true;
  throw DeviceFailure(call, result_name(r));
}

void XrBackend::fail(const renderer::VulkanFailure& f) {
  failed_ = true;
  throw DeviceFailure(f.call, renderer::vk_result_name(f.result), "rendering for the headset");
}

void XrBackend::on_state(SessionState next) {
  const RunMode before = state_.mode();
  const SessionUpdate u = state_.on_state_changed(next);
  // While leaving on our own request, the step-down is expected: no pause
  // or exit messages for the experimenter.
  if (!u.message.empty() && !leaving_) std::cerr << "curvlab: xr: " << u.message << '\n';
  if (u.begin_session) {
    auto info = tagged<XrSessionBeginInfo>(XR_TYPE_SESSION_BEGIN_INFO);
    info.primaryViewConfigurationType = kViewConfig;
    if (const XrResult r = xrBeginSession(session_.get(), &info); XR_FAILED(r)) fail(r, "xrBeginSession");
  }
  if (u.end_session) {
    if (frame_begun_) (void)end_frame(FrameLayer::none);  // the session is ending: only xrEndSession counts
    if (const XrResult r = xrEndSession(session_.get()); XR_FAILED(r))
      std::cerr << "curvlab: xr: " << failure_of(r, "xrEndSession").message << '\n';
  }
  if (u.mode != RunMode::Running && before == RunMode::Running) {
    // Inactive while unfocused; the return syncs afresh.
    for (auto& hands : active_) hands = {false, false};
    synced_ = false;
  }
  // The wait for the first focus (the pause READY gives) is the runner's
  // only once a frame has ended without focus: most runtimes bring
  // SYNCHRONIZED, VISIBLE and FOCUSED right after the first frame, and then
  // the first trial runs with no pause at all.
  if (u.pause && next == SessionState::Ready) focus_wait_ = true;
  else if (u.pause) signals_.push_back(Signal::pause);
  if (u.resume && focus_wait_) focus_wait_ = false;
  else if (u.resume) signals_.push_back(Signal::resume);
  if (u.mode == RunMode::Exit) signals_.push_back(Signal::quit);
}

bool XrBackend::poll_events() {
  for (;;) {
    auto event = tagged<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
    const XrResult r = xrPollEvent(instance_.handle(), &event);
    if (r == XR_EVENT_UNAVAILABLE) break;
    if (XR_FAILED(r)) fail(r, "xrPollEvent");
    switch (event.type) {
      case XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED: {
        const auto& e = *reinterpret_cast<const XrEventDataSessionStateChanged*>(&event);
        if (e.state == XR_SESSION_STATE_FOCUSED) focused_at_ = e.time;
        on_state(static_cast<SessionState>(e.state));
        break;
      }
      case XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING:
        failed_ = true;
        throw DeviceFailure("xrPollEvent", "XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING",
                             "the OpenXR runtime is going away");
      case XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING:
        on_stage_change(*reinterpret_cast<const XrEventDataReferenceSpaceChangePending*>(&event));
        break;
      case XR_TYPE_EVENT_DATA_EVENTS_LOST:
        on_events_lost(*reinterpret_cast<const XrEventDataEventsLost*>(&event));
        break;
      case XR_TYPE_EVENT_DATA_DISPLAY_REFRESH_RATE_CHANGED_FB:
        on_refresh_rate_changed(*reinterpret_cast<const XrEventDataDisplayRefreshRateChangedFB*>(&event));
        break;
      default:
        break;
    }
  }
  return !failed_ && state_.mode() != RunMode::Exit;
}

// The runtime's queue overflowed and dropped events (OpenXR 1.0 §2.22).
// Nothing says which; the session states that matter come again with the
// next change, so the session goes on, and the loss is data.
void XrBackend::on_events_lost(const XrEventDataEventsLost& e) {
  std::cerr << "curvlab: xr: the OpenXR runtime dropped " << e.lostEventCount
            << " event(s) it could not queue; the session goes on (recorded as an events_lost event)\n";
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::events_lost;
  report.lost_events = e.lostEventCount;
  reports_.push_back(report);
}

// The runtime moves STAGE's origin (a redrawn play area or boundary): from
// changeTime on its poses are in the new origin. The room and the table did
// not move, and the table's calibration is in the lab frame (the STAGE
// before the move), so where the runtime says where the new origin lies,
// curvlab keeps the lab frame: it locates in a STAGE space offset by the
// inverse of the move, from the first frame displayed at or after
// changeTime. Where the runtime does not know the move, the table may have
// moved under the participant: the attempt is dropped (recenter) and the
// experimenter told to check the calibration.
void XrBackend::on_stage_change(const XrEventDataReferenceSpaceChangePending& e) {
  if (e.referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE) return;
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::stage_moved;
  report.change_ns = to_session_ns(e.changeTime);
  report.pose_valid = e.poseValid == XR_TRUE;
  const XrPosef& p = e.poseInPreviousSpace;
  report.origin = {p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z,
                   p.orientation.w};
  if (report.pose_valid) {
    // poseInReferenceSpace Q keeps lab coordinates: lab = Q⁻¹ · stage. With
    // the old stage = P · new stage (P the new origin in the old), the new
    // space needs Q' = P⁻¹ · Q.
    const LabPose moved = to_lab_pose(p);
    const LabPose before = to_lab_pose(stage_next_.get() != XR_NULL_HANDLE ? stage_next_offset_ : stage_offset_);
    const glm::dquat inv = glm::inverse(glm::normalize(moved.orientation));
    LabPose offset;
    offset.orientation = inv * before.orientation;
    offset.position_m = inv * (before.position_m - moved.position_m);
    auto info = tagged<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
    info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
    info.poseInReferenceSpace = to_xr_pose(offset);
    SpaceHandle next;
    if (const XrResult r = xrCreateReferenceSpace(session_.get(), &info, next.out()); XR_SUCCEEDED(r)) {
      stage_next_ = std::move(next);
      stage_next_offset_ = info.poseInReferenceSpace;
      stage_change_at_ = e.changeTime;
      report.kept_lab_frame = true;
    } else if (fatal(r)) {
      fail(r, "xrCreateReferenceSpace");
    }
  }
  if (report.kept_lab_frame) {
    std::cerr << "curvlab: xr: the runtime moved its STAGE origin (a new play area or boundary) by (" << p.position.x
              << ", " << p.position.y << ", " << p.position.z
              << ") m; curvlab keeps the lab frame where it was, so the table calibration still holds\n";
  } else {
    std::cerr << "curvlab: xr: the runtime moved its STAGE origin (a new play area or boundary) without saying "
                 "where; the trial is run again: check that the table is where the participant sees it, and "
                 "calibrate again (curvlab calibrate) if not\n";
    signals_.push_back(Signal::recenter);
  }
  reports_.push_back(report);
}

void XrBackend::follow_stage_change(XrTime t) {
  if (stage_next_.get() == XR_NULL_HANDLE || t < stage_change_at_) return;
  stage_ = std::move(stage_next_);
  stage_offset_ = stage_next_offset_;
}

// The display's rate changed. Frames follow the runtime's period at once
// (each frame's is stored); a change the lab did not ask for is said,
// recorded, and the protocol's rate asked for again.
void XrBackend::on_refresh_rate_changed(const XrEventDataDisplayRefreshRateChangedFB& e) {
  const double to = static_cast<double>(e.toDisplayRefreshRate);
  if (requested_hz_ > 0.0f && e.toDisplayRefreshRate == requested_hz_ && std::abs(refresh_hz_ - to) < 0.5) {
    requested_hz_ = 0.0f;  // the change curvlab asked for, already recorded
    return;
  }
  std::cerr << "curvlab: xr: the headset changed its refresh rate from " << e.fromDisplayRefreshRate << " to "
            << e.toDisplayRefreshRate << " Hz\n";
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::refresh_rate;
  report.from_hz = e.fromDisplayRefreshRate;
  report.to_hz = to;
  reports_.push_back(report);
  refresh_hz_ = to;
  requested_hz_ = 0.0f;
  request_refresh_rate();
}

// CLOCK_MONOTONIC → session clock. Reading the two clocks one after the
// other adds any preemption between the reads to the result, so the offset
// comes from the tightest of a few bracketed reads (monotonic, session,
// monotonic), kept for 5 s.
std::int64_t XrBackend::monotonic_to_session() {
  const std::int64_t mono = monotonic_now_ns();
  if (offset_at_ns_ >= 0 && mono - offset_at_ns_ < 5'000'000'000) return offset_ns_;
  std::int64_t narrowest = std::numeric_limits<std::int64_t>::max();
  for (int i = 0; i < 5; ++i) {
    const std::int64_t before = monotonic_now_ns();
    const std::int64_t session = options_.clock->now_ns();
    const std::int64_t after = monotonic_now_ns();
    if (after - before < narrowest) {
      narrowest = after - before;
      offset_ns_ = session - (before + (after - before) / 2);
    }
  }
  offset_at_ns_ = mono;
  return offset_ns_;
}

std::int64_t XrBackend::to_session_ns(XrTime t) {
  if (to_timespec_ != nullptr) {
    timespec ts{};
    if (XR_SUCCEEDED(to_timespec_(instance_.handle(), t, &ts)))
      return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec + monotonic_to_session();
  }
#ifdef _WIN32
  if (to_counter_ != nullptr) {
    LARGE_INTEGER counter;
    if (XR_SUCCEEDED(to_counter_(instance_.handle(), t, &counter)))
      return counter_ns(counter.QuadPart) + monotonic_to_session();
  }
#endif
  return clock_map_.to_session(t);
}

// A held layer names the same swapchains with the views their images were
// rendered for: the compositor shows each swapchain's last released image
// (OpenXR 1.0 §10.5, "Swapchain Image Management"), reprojected to the head
// of now, so the participant keeps seeing the last frame, world-locked.
XrResult XrBackend::end_frame(FrameLayer what) {
  if (what == FrameLayer::fresh) shown_views_ = views_;
  if (what == FrameLayer::held && !shown_views_) what = FrameLayer::none;
  const bool with_layer = what != FrameLayer::none;
  const std::array<XrView, 2>& from = what == FrameLayer::fresh || !shown_views_ ? views_ : *shown_views_;
  std::array<XrCompositionLayerProjectionView, 2> views{};
  for (std::size_t i = 0; i < 2; ++i) {
    views[i] = tagged<XrCompositionLayerProjectionView>(XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW);
    views[i].pose = from[i].pose;
    views[i].fov = from[i].fov;
    views[i].subImage.swapchain = swapchains_[i].handle.get();
    views[i].subImage.imageRect = {{0, 0},
                                   {static_cast<std::int32_t>(swapchains_[i].width),
                                    static_cast<std::int32_t>(swapchains_[i].height)}};
    views[i].subImage.imageArrayIndex = 0;
  }
  auto layer = tagged<XrCompositionLayerProjection>(XR_TYPE_COMPOSITION_LAYER_PROJECTION);
  layer.space = stage_.get();
  layer.viewCount = 2;
  layer.views = views.data();
  const auto* header = reinterpret_cast<const XrCompositionLayerBaseHeader*>(&layer);
  auto info = tagged<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
  info.displayTime = frame_state_.predictedDisplayTime;
  info.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  info.layerCount = with_layer ? 1 : 0;
  info.layers = with_layer ? &header : nullptr;
  frame_begun_ = false;
  ++frames_ended_;
  return xrEndFrame(session_.get(), &info);
}

std::optional<FrameTiming> XrBackend::begin_frame() {
  // Until the runtime makes the session READY there is no frame loop; wait
  // for its events (the runner shows nothing meanwhile). Once the runtime
  // has stopped a session that ran (STOPPING, then IDLE until it is READY
  // again), the runner keeps its own loop, paused, on frames without OpenXR.
  for (;;) {
    if (!poll_events()) return std::nullopt;
    if (state_.session_running()) break;
    if (state_.mode() == RunMode::Stopped) return stopped_frame();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // A frame the runner began but did not draw (it paused, aborted or quit
  // there) ends with the last image held.
  if (frame_begun_)
    if (const XrResult r = end_frame(undrawn()); XR_FAILED(r)) fail(r, "xrEndFrame");
  const XrSession session = session_.get();
  auto wait_info = tagged<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
  frame_state_ = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  if (const XrResult r = xrWaitFrame(session, &wait_info, &frame_state_); XR_FAILED(r)) fail(r, "xrWaitFrame");
  const std::int64_t now = options_.clock->now_ns();
  auto begin_info = tagged<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
  if (const XrResult r = xrBeginFrame(session, &begin_info); XR_FAILED(r)) fail(r, "xrBeginFrame");
  frame_begun_ = true;
  const XrTime t = frame_state_.predictedDisplayTime;
  follow_stage_change(t);
  // Without XR_KHR_convert_timespec_time: the first frame's image is taken
  // to appear one period after xrWaitFrame returned (docs/lab.md).
  if (to_timespec_ == nullptr && !clock_map_.anchored())
    clock_map_.anchor(t, now + frame_state_.predictedDisplayPeriod);

  synced_ = false;
  if (state_.mode() == RunMode::Running) sync_actions();

  // Views and devices where they will be when this frame is seen.
  auto locate_info = tagged<XrViewLocateInfo>(XR_TYPE_VIEW_LOCATE_INFO);
  locate_info.viewConfigurationType = kViewConfig;
  locate_info.displayTime = t;
  locate_info.space = stage_.get();
  auto view_state = tagged<XrViewState>(XR_TYPE_VIEW_STATE);
  std::uint32_t n = 0;
  views_ = {tagged<XrView>(XR_TYPE_VIEW), tagged<XrView>(XR_TYPE_VIEW)};
  const XrResult located_views = xrLocateViews(session, &locate_info, &view_state, 2, &n, views_.data());
  if (fatal(located_views)) fail(located_views, "xrLocateViews");
  views_valid_ = XR_SUCCEEDED(located_views) && n == 2 &&
                 (view_state.viewStateFlags & XR_VIEW_STATE_POSITION_VALID_BIT) != 0 &&
                 (view_state.viewStateFlags & XR_VIEW_STATE_ORIENTATION_VALID_BIT) != 0;
  auto locate = [&](XrSpace space) {
    auto loc = tagged<XrSpaceLocation>(XR_TYPE_SPACE_LOCATION);
    const XrResult r = xrLocateSpace(space, stage_.get(), t, &loc);
    if (fatal(r)) fail(r, "xrLocateSpace");
    return std::pair{to_lab_pose(loc.pose), XR_SUCCEEDED(r) ? loc.locationFlags : XrSpaceLocationFlags{0}};
  };
  const auto [head, head_flags] = locate(view_.get());
  head_ = head;
  head_flags_ = head_flags;
  lab_[geometry::Device::head] = to_geometry(head, usable(head_flags));
  for (std::size_t i = 0; i < 2; ++i) {
    const auto [hand, hand_flags] = locate(grip_[i].get());
    auto& pose = lab_[i == 0 ? geometry::Device::left_hand : geometry::Device::right_hand];
    pose = to_geometry(hand, located(hand_flags));
    pose.orientation_valid = orientation_located(hand_flags);
  }
  gaze_.reset();
  if (eyes_->any()) {
    auto found = eyes_->locate(stage_.get(), t, head);
    if (found.fatal != XR_SUCCESS) fail(found.fatal, found.call);
    gaze_ = std::move(found.gaze);
  }

  FrameTiming timing;
  timing.index = frame_index_++;
  timing.now_ns = now;
  timing.predicted_display_ns = to_session_ns(t);
  timing.period_ns = frame_state_.predictedDisplayPeriod;
  mark_late(timing);
  return timing;
}

// A frame of the runner's loop while the runtime has the session stopped:
// paced at the display's period, nothing located (the head and hands are
// untracked, the eyes from the IPD), nothing submitted (submit() finds no
// begun frame), and late, since nothing is shown. The pause it carries
// (SessionUpdate::pause) stops the trial's clock at the STOPPING, not when
// the runtime makes the session READY again; the runner stays free to quit.
FrameTiming XrBackend::stopped_frame() {
  const std::int64_t period = frame_state_.predictedDisplayPeriod > 0
                                  ? frame_state_.predictedDisplayPeriod
                                  : static_cast<std::int64_t>(1e9 / refresh_hz_);
  std::this_thread::sleep_for(std::chrono::nanoseconds(period));
  views_valid_ = false;
  head_flags_ = 0;
  for (auto& pose : lab_.pose) pose.valid = false;
  gaze_.reset();
  last_display_ = 0;  // the display times after the restart start afresh
  FrameTiming timing;
  timing.index = frame_index_++;
  timing.now_ns = options_.clock->now_ns();
  timing.predicted_display_ns = timing.now_ns + period;
  timing.period_ns = period;
  timing.late = true;
  return timing;
}

// A frame is late when its display time skipped refreshes after the
// previous frame's (the loop missed them: the previous image stayed up
// longer) or the runtime said not to render it (it is not shown).
void XrBackend::mark_late(FrameTiming& timing) {
  const XrTime t = frame_state_.predictedDisplayTime;
  const XrDuration period = frame_state_.predictedDisplayPeriod;
  if (last_display_ != 0 && period > 0 && t > last_display_)
    timing.skipped_periods = static_cast<std::int32_t>(
        std::max<std::int64_t>(0, std::llround(static_cast<double>(t - last_display_) / static_cast<double>(period)) - 1));
  last_display_ = t;
  timing.late = timing.skipped_periods > 0 || frame_state_.shouldRender != XR_TRUE;
}

geometry::LabFrame XrBackend::poses(const FrameTiming& frame) {
  (void)frame;  // located in begin_frame at this frame's predicted display time
  return lab_;
}

harness::io::HeadTracking XrBackend::head_tracking() const {
  return {(head_flags_ & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT) != 0,
          (head_flags_ & XR_SPACE_LOCATION_POSITION_TRACKED_BIT) != 0};
}

std::string XrBackend::describe_head_tracking() const {
  return location_flags_text(head_flags_) + " (xrLocateSpace of the VIEW space)";
}

renderer::StereoRig XrBackend::rig(const FrameTiming& frame, double ipd_m) {
  (void)frame;
  if (!views_valid_) return renderer::StereoRig::from_ipd(ipd_m, renderer::Fov{});
  return rig_from_views(head_, {to_lab_pose(views_[0].pose), to_lab_pose(views_[1].pose)},
                        {to_fov(views_[0].fov), to_fov(views_[1].fov)});
}

void XrBackend::report_once(XrResult r, const char* call) {
  if (fatal(r)) fail(r, call);
  if (std::find(reported_.begin(), reported_.end(), call) != reported_.end()) return;
  reported_.emplace_back(call);
  std::cerr << "curvlab: xr: " << failure_of(r, call).message << '\n';
}

void XrBackend::sync_actions() {
  // curvlab's action set, and the eye gaze's where there is one.
  const std::array<XrActiveActionSet, 2> active{{{actions_->handle(), XR_NULL_PATH},
                                                 {eyes_->action_set(), XR_NULL_PATH}}};
  auto sync = tagged<XrActionsSyncInfo>(XR_TYPE_ACTIONS_SYNC_INFO);
  sync.countActiveActionSets = eyes_->action_set() != XR_NULL_HANDLE ? 2 : 1;
  sync.activeActionSets = active.data();
  if (const XrResult r = xrSyncActions(session_.get(), &sync); fatal(r)) fail(r, "xrSyncActions");
  else if (XR_FAILED(r)) std::cerr << "curvlab: xr: " << failure_of(r, "xrSyncActions").message << '\n';
  synced_ = true;
}

// Action states are those of the last xrSyncActions (OpenXR 1.0 §11.5). The
// frame on which focus returns began unfocused, without a sync: its states
// would be the ones synced before the focus loss, so it syncs here. An
// action that was inactive (no focus) gives its first state as a baseline,
// not an event: a button or trigger held across the focus return is no new
// press, and nothing that changed before the return is delivered.
void XrBackend::read_buttons(std::vector<InputEvent>& out) {
  if (!synced_) sync_actions();
  const XrSession session = session_.get();
  const auto def = curvlab_action_set();
  for (std::size_t k = 0; k < def.actions.size(); ++k) {
    const auto& a = def.actions[k];
    if (a.type == ActionType::Pose) continue;
    for (const auto& sub : a.subaction_paths) {
      const std::size_t hand = sub == kLeftHand ? 0 : 1;
      bool& was_active = active_[k][hand];
      auto get = tagged<XrActionStateGetInfo>(XR_TYPE_ACTION_STATE_GET_INFO);
      get.action = actions_->action(a.name);
      get.subactionPath = hand_paths_[hand];
      const std::string device = hand == 0 ? "xr:left" : "xr:right";
      // Events carry the protocol's button names (docs/protocols.md, "Key
      // and button names"), which is what judgement options bind.
      const std::string name = protocol_button(a.name, hand == 0);
      if (a.type == ActionType::Boolean) {
        auto st = tagged<XrActionStateBoolean>(XR_TYPE_ACTION_STATE_BOOLEAN);
        if (const XrResult r = xrGetActionStateBoolean(session, &get, &st); XR_FAILED(r)) {
          report_once(r, "xrGetActionStateBoolean");
          continue;
        }
        const bool baseline = !was_active;
        was_active = st.isActive == XR_TRUE;
        if (st.isActive == XR_TRUE && st.changedSinceLastSync == XR_TRUE && !baseline &&
            st.lastChangeTime >= focused_at_) {
          const std::int64_t t_ns = to_session_ns(st.lastChangeTime);
          out.push_back({t_ns, name, device, st.currentState == XR_TRUE});
          // A continues pages as the trigger does (controller_reach).
          if (name == "a") out.push_back({t_ns, "continue", device, st.currentState == XR_TRUE});
        }
      } else {
        auto st = tagged<XrActionStateFloat>(XR_TYPE_ACTION_STATE_FLOAT);
        if (const XrResult r = xrGetActionStateFloat(session, &get, &st); XR_FAILED(r)) {
          report_once(r, "xrGetActionStateFloat");
          continue;
        }
        const bool baseline = !was_active;
        was_active = st.isActive == XR_TRUE;
        if (st.isActive != XR_TRUE) continue;
        const bool was = trigger_down_[hand];
        const bool now = was ? st.currentState > kTriggerRelease : st.currentState > kTriggerPress;
        if (baseline) trigger_down_[hand] = st.currentState > kTriggerPress;
        if (baseline || now == was) continue;
        trigger_down_[hand] = now;
        const std::int64_t t_ns = to_session_ns(st.lastChangeTime);
        out.push_back({t_ns, name, device, now});
        // The trigger also advances instruction pages and breaks, which
        // follow a button named "continue" (io/frame.hpp, Overlay).
        out.push_back({t_ns, "continue", device, now});
      }
    }
  }
}

Signal XrBackend::poll(std::vector<InputEvent>& out) {
  if (!failed_ && state_.mode() == RunMode::Running) read_buttons(out);
  return Signal::none;
}

Signal XrBackend::poll_signal() {
  if (!failed_) poll_events();
  if (focus_wait_ && frames_ended_ > 0) {
    signals_.push_back(Signal::pause);
    focus_wait_ = false;
  }
  if (signals_.empty()) return Signal::none;
  // Quit outranks everything still queued.
  if (std::find(signals_.begin(), signals_.end(), Signal::quit) != signals_.end()) {
    signals_.clear();
    return Signal::quit;
  }
  const Signal s = signals_.front();
  signals_.pop_front();
  return s;
}

renderer::FrameStats XrBackend::submit(const renderer::Scene& scene,
                                       const renderer::FrameDescription& frame,
                                       const Overlay& overlay, bool draw) {
  // The headset shows every frame: `draw` cannot skip one.
  (void)overlay;
  (void)draw;
  renderer::FrameStats stats;
  if (!frame_begun_) return stats;
  const bool render = frame_state_.shouldRender == XR_TRUE && views_valid_;
  if (!render) {
    if (const XrResult r = end_frame(undrawn()); XR_FAILED(r)) fail(r, "xrEndFrame");
    return stats;
  }
  std::array<bool, 2> acquired{false, false};
  std::array<vk::Image, 2> submitted{};
  auto release_all = [&] {
    for (std::size_t i = 0; i < 2; ++i) {
      if (!acquired[i]) continue;
      auto info = tagged<XrSwapchainImageReleaseInfo>(XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO);
      (void)xrReleaseSwapchainImage(swapchains_[i].handle.get(), &info);
    }
  };
  for (std::size_t i = 0; i < 2; ++i) {
    EyeSwapchain& sc = swapchains_[i];
    std::uint32_t index = 0;
    auto acquire = tagged<XrSwapchainImageAcquireInfo>(XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO);
    if (const XrResult r = xrAcquireSwapchainImage(sc.handle.get(), &acquire, &index); XR_FAILED(r)) {
      release_all();
      fail(r, "xrAcquireSwapchainImage");  // the destructor ends the begun frame
    }
    acquired[i] = true;
    try {
      wait_image(sc.handle.get());
    } catch (const DeviceFailure&) {
      // A waited image is released by release_all; one the wait never
      // got is not (the runtime refuses it): the frame is lost either way.
      acquired[i] = false;
      release_all();
      throw;
    }
    submitted[i] = sc.images[index].image;
    target_->set_image(i == 0 ? renderer::Eye::left : renderer::Eye::right,
                       {sc.images[index].image, static_cast<vk::Format>(swapchain_format_),
                        vk::Extent2D{sc.width, sc.height},
                        vk::ImageLayout::eColorAttachmentOptimal});
  }
  renderer::FrameDescription f = frame;
  f.width_px = swapchains_[0].width;
  f.height_px = swapchains_[0].height;
  try {
    // render() submits before returning, as xrReleaseSwapchainImage requires.
    stats = renderer_->render(scene, f, *target_);
    // The operator window's copy, while the images are still acquired.
    if (mirror_) mirror_->copy(submitted);
  } catch (const renderer::VulkanFailure& e) {
    release_all();
    fail(e);
  } catch (const vk::SystemError& e) {
    release_all();
    fail(renderer::VulkanFailure(renderer::vk_call_name(e.what()), e.code().value()));
  }
  release_all();
  if (const XrResult r = end_frame(FrameLayer::fresh); XR_FAILED(r)) fail(r, "xrEndFrame");
  return stats;
}

void XrBackend::wait_image(XrSwapchain swapchain) {
  // XR_TIMEOUT_EXPIRED is a success code: the image is not yet the
  // application's (OpenXR 1.0 §10.1, xrWaitSwapchainImage), so it is waited
  // again, and a wait past kLimit is a failure of the compositor.
  constexpr XrDuration kStep = 250'000'000, kLimit = 5'000'000'000;
  auto wait = tagged<XrSwapchainImageWaitInfo>(XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO);
  wait.timeout = kStep;
  for (XrDuration waited = 0;; waited += kStep) {
    const XrResult r = xrWaitSwapchainImage(swapchain, &wait);
    if (XR_FAILED(r)) fail(r, "xrWaitSwapchainImage");
    if (r != XR_TIMEOUT_EXPIRED) return;
    if (!swapchain_wait_said_) {
      std::cerr << "curvlab: xr: the compositor has held a swapchain image for more than " << kStep / 1'000'000
                << " ms; waiting for it\n";
      swapchain_wait_said_ = true;
    }
    if (waited + kStep >= kLimit) fail(XR_TIMEOUT_EXPIRED, "xrWaitSwapchainImage");
  }
}

std::vector<std::string> XrBackend::save_frame(const std::string& stem) {
  std::vector<std::string> written;
  try {
    for (const auto eye : {renderer::Eye::left, renderer::Eye::right}) {
      const auto image = target_->read_eye(eye);
      if (!image) continue;
      const std::string path = stem + (eye == renderer::Eye::left ? "_left.png" : "_right.png");
      const auto saved = renderer::write_png(path, *image);
      if (const auto* err = std::get_if<renderer::RenderError>(&saved)) {
        std::cerr << "curvlab: xr: frame not saved: " << err->message << '\n';
        continue;
      }
      written.push_back(path);
    }
  } catch (const renderer::VulkanFailure& e) {
    fail(e);
  } catch (const vk::SystemError& e) {
    fail(renderer::VulkanFailure(renderer::vk_call_name(e.what()), e.code().value()));
  }
  return written;
}

harness::io::Reach controller_reach() {
  harness::io::Reach r;
  for (const auto& a : curvlab_action_set().actions) {
    if (a.type == ActionType::Pose) continue;
    for (const auto& path : a.subaction_paths) r.buttons.push_back(protocol_button(a.name, path == kLeftHand));
  }
  r.continue_phrase = "pull a trigger or press A";
  return r;
}

Result<std::unique_ptr<InteractiveDisplay>> make_xr_backend(const XrBackendOptions& options) {
  return XrBackend::create(options);
}

}  // namespace curvlab::xr
