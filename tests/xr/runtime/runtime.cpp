// curvlab's OpenXR runtime for tests: a scripted headset that the real
// Khronos loader loads through XR_RUNTIME_JSON (the manifest is generated in
// the build folder next to this library), so the real `curvlab run --backend
// xr` drives a whole session on a machine without a headset. It implements
// every OpenXR 1.0 core function, XR_KHR_vulkan_enable2,
// XR_KHR_convert_timespec_time (Khronos' hello_xr runs through it; built
// for Windows XR_KHR_win32_convert_performance_counter_time instead, as
// Windows runtimes offer) and XR_FB_display_refresh_rate, with scripted eyes also
// XR_EXT_eye_gaze_interaction and XR_FB_eye_tracking_social (eyes.hpp), and
// checks the rules of the OpenXR 1.0 specification that are cheap to check
// (call order of the frame loop and of swapchain images, session states,
// action-set attachment, action types and subaction paths, layers
// referencing released images, …). A broken rule
// returns the specification's error and writes a "violation" line to the log
// and to stderr, so a test fails even where the application ignores a result.
//
// Environment (all optional):
//   CURVLAB_TEST_XR_PRESS    controller presses, comma-separated
//                            HAND:BUTTON@SECONDS[/EVERY][~HOLD], e.g.
//                            "right:a@1.0/1.2,left:x@1.6/1.2" (HAND left|right;
//                            BUTTON a b x y menu trigger squeeze; SECONDS after
//                            the session first became FOCUSED; repeated every
//                            EVERY s; held HOLD s, default 0.08)
//   CURVLAB_TEST_XR_HAND     hand placements, semicolon-separated
//                            HAND@SECONDS=X,Y,Z: from SECONDS after focus on,
//                            that hand's grip is at (X, Y, Z) in STAGE,
//                            unrotated, until its next placement (before
//                            the first: resting on the table's near edge)
//   CURVLAB_TEST_XR_UNFOCUS  spells without input focus, SECONDS+DURATION,
//                            comma-separated: FOCUSED → VISIBLE → FOCUSED
//   CURVLAB_TEST_XR_EXIT     SECONDS: the runtime asks the application to exit
//                            (VISIBLE, SYNCHRONIZED, STOPPING; after
//                            xrEndSession IDLE and EXITING)
//   CURVLAB_TEST_XR_RESTART  SECONDS+IDLE: the runtime stops the session
//                            (VISIBLE, SYNCHRONIZED, STOPPING); after
//                            xrEndSession it is IDLE for IDLE seconds, then
//                            READY; after xrBeginSession and a frame,
//                            SYNCHRONIZED, VISIBLE and FOCUSED again
//   CURVLAB_TEST_XR_LOSS     SECONDS: the session is being lost (LOSS_PENDING,
//                            from any state; xrWaitFrame and xrEndFrame
//                            return XR_ERROR_SESSION_LOST half a second later)
//   CURVLAB_TEST_XR_FAIL     CALL@SECONDS:RESULT: from SECONDS after focus on,
//                            CALL (xrWaitFrame or xrEndFrame) returns RESULT
//                            (XR_ERROR_SESSION_LOST, XR_ERROR_RUNTIME_FAILURE
//                            or XR_ERROR_INSTANCE_LOST), as a runtime whose
//                            session or compositor died does; a "fault" line
//                            in the log
//   CURVLAB_TEST_XR_HEAD     tracked (default) or orientation_only: the head
//                            (VIEW space, views) is located with its
//                            position valid but not tracked, its orientation
//                            tracked, as Monado's simulated headset reports
//   CURVLAB_TEST_XR_CAPTURE_DIR   write the left eye of submitted frames here
//                            as PNG (left_<frame>_<monotonic ns>.png, the
//                            frame's predicted display time on CLOCK_MONOTONIC):
//                            the projection layer with the quad layers laid
//                            over it, a "quad" log line for each of these
//   CURVLAB_TEST_XR_CAPTURE_EVERY every n-th submitted frame (default 1)
//   CURVLAB_TEST_XR_LOG      a text log: one "frame" line per xrWaitFrame with
//                            the predicted display time (XrTime and
//                            CLOCK_MONOTONIC ns) and the head pose at it; one
//                            "end_frame N layers K state S should_render R"
//                            line per xrEndFrame that succeeded (S the
//                            session state then, R the frame's shouldRender); "sync_actions frame N focused F" per
//                            xrSyncActions and "action_state CALL ACTION frame
//                            N focused F" per action-state query (N the frame
//                            of the last xrWaitFrame, F 1 while FOCUSED);
//                            "state", "profile", "input", "haptic",
//                            "capture", "violation", "warning" lines
//   CURVLAB_TEST_XR_SIZE     recommended eye size WxH (default 320x320)
//   CURVLAB_TEST_XR_LATE     late frames, comma-separated, numbered from 0 in
//                            xrWaitFrame order: FRAME wakes the application a
//                            period late, so its predicted display time skips
//                            one refresh; FRAME! returns shouldRender false
//   CURVLAB_TEST_XR_TIMING   jitter=MS,miss=P,seed=N (any of them): predicted
//                            display times within ±MS of the display grid,
//                            and a wake-up that misses a refresh with
//                            probability P per frame, both a pure function of
//                            (N, frame number); a "pacing" line per such frame
//   CURVLAB_TEST_XR_SWAPCHAIN_WAIT MS/EVERY: every EVERY-th image acquired from
//                            a swapchain is read by the compositor for MS ms:
//                            xrWaitSwapchainImage waits for it, or returns
//                            XR_TIMEOUT_EXPIRED after a shorter timeout; a
//                            "swapchain_wait" line each time
//   CURVLAB_TEST_XR_STATES   ready=S,visible=N,focused=N (any of them): READY
//                            S seconds after xrCreateSession, SYNCHRONIZED
//                            after the first xrEndFrame, VISIBLE N frames
//                            later, FOCUSED N frames after that (default: at
//                            once); the same after a RESTART
//   CURVLAB_TEST_XR_STAGE_MOVE SECONDS=X,Y,Z[,YAW_DEG][!]: STAGE's origin moves
//                            to that pose in the previous STAGE, announced
//                            (REFERENCE_SPACE_CHANGE_PENDING) 0.1 s before;
//                            the room, head, hands and table stay; ! sends
//                            poseValid false; a "stage_move" line
//   CURVLAB_TEST_XR_EVENTS_LOST SECONDS[xCOUNT]: the event queue overflows,
//                            XrEventDataEventsLost with COUNT (default 1)
//   CURVLAB_TEST_XR_FORMATS  swapchain formats offered, in this order: names
//                            among R8G8B8A8_SRGB B8G8R8A8_SRGB R8G8B8A8_UNORM
//                            B8G8R8A8_UNORM (default all four, sRGB first); a
//                            "swapchain format F WxH" line per swapchain
//   CURVLAB_TEST_XR_VIEWS    cant=DEG,ipd=MIN:MAX,fov=F (any of them): eyes
//                            turned DEG outward (canted displays), an IPD in
//                            [MIN, MAX] m and fields of view scaled by up to
//                            ±F, changing every frame; a "views" line per
//                            display time (each eye: pose relative to the head,
//                            x y z qx qy qz qw, field of view l r u d)
//   CURVLAB_TEST_XR_TRACKING partial tracking, DEVICE:MODE@SECONDS+DURATION,
//                            comma-separated: DEVICE head, left or right; MODE
//                            inferred (valid, not tracked), orientation_only
//                            (position not valid) or lost; a pose that is not
//                            valid is reported far from the true one
//   CURVLAB_TEST_XR_REFRESH  XR_FB_display_refresh_rate (always offered): the
//                            rates and the starting one, RATES[@START] in Hz
//                            (default 90); a request changes the rate at once
//                            ("refresh_request" and "refresh_rate" lines)
//   CURVLAB_TEST_XR_REFRESH_CHANGE SECONDS=HZ: the runtime changes the rate
//                            itself (XrEventDataDisplayRefreshRateChangedFB)
//   CURVLAB_TEST_XR_GAZE     eye tracking, KIND:TARGET[:LEFT,RIGHT] (eyes.hpp):
//                            KIND both, per_eye (XR_FB_eye_tracking_social)
//                            or combined (XR_EXT_eye_gaze_interaction) says
//                            which extensions are offered; TARGET
//                            fixate=X,Y,Z (both eyes on that STAGE point) or
//                            vergence=DEGREES (held about the head's forward
//                            direction, negative diverging); LEFT,RIGHT the
//                            per-eye confidences (default 1). The eyes are
//                            tracked while FOCUSED. Unset: neither extension
//                            is offered
//
// XrTime is CLOCK_MONOTONIC minus an epoch taken when the library loads (so
// the two differ, and xrConvertTimeToTimespecTimeKHR has work to do).
// xrWaitFrame blocks until the next refresh of the display's grid that has
// not passed (90 Hz, or the rate in force); the predicted display time is a
// period after it. A second xrWaitFrame before xrBeginFrame, which a runtime
// blocks until the frame is begun (for ever on one thread), is a violation.
//
// Not thread-safe beyond a global lock: one application thread at a time.
#include "eyes.hpp"
#include "profiles.hpp"
#include "script.hpp"

#include <time.h>

#include <chrono>
#include <thread>

#define VK_NO_PROTOTYPES
#include <vulkan/vulkan.h>
#define XR_NO_PROTOTYPES
#define XR_USE_GRAPHICS_API_VULKAN
#define XR_USE_TIMESPEC
#ifdef _WIN32
#include <windows.h>
#define XR_USE_PLATFORM_WIN32
#endif
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include "curvlab/harness/xr/fb_eye_tracking_social.hpp"

#include <stb_image_write.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "loader_interface.hpp"

extern "C" {
__attribute__((visibility("default"))) XrResult xrNegotiateLoaderRuntimeInterface(
    const XrNegotiateLoaderInfo* loaderInfo, XrNegotiateRuntimeRequest* runtimeRequest);
}

namespace curvlab::test_runtime {
namespace {

constexpr std::uint32_t kLoaderInfoVersion = 1;
constexpr std::uint32_t kRuntimeRequestVersion = 1;
constexpr std::uint32_t kRuntimeInterfaceVersion = 1;
constexpr XrSystemId kSystem = 0x5e5;
constexpr std::uint32_t kImagesPerSwapchain = 3;
constexpr std::uint32_t kMaxLayers = 16;
constexpr std::uint32_t kMaxSwapchainPx = 4096;

std::int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

// XrTime = CLOCK_MONOTONIC − epoch.
const std::int64_t g_epoch_ns = monotonic_ns() - 1'000'000'000;
XrTime to_xr(std::int64_t mono_ns) { return mono_ns - g_epoch_ns; }
std::int64_t to_mono(XrTime t) { return t + g_epoch_ns; }
double xr_seconds(XrTime t) { return static_cast<double>(t) * 1e-9; }

std::string result_name(XrResult r) {
#define CURVLAB_RT_RESULT(name, value) \
  case name:                           \
    return #name;
  switch (r) {
    XR_LIST_ENUM_XrResult(CURVLAB_RT_RESULT)
    default:
      break;
  }
#undef CURVLAB_RT_RESULT
  return "XR_RESULT_" + std::to_string(static_cast<int>(r));
}

std::string state_name(XrSessionState s) {
#define CURVLAB_RT_STATE(name, value) \
  case name:                          \
    return #name;
  switch (s) {
    XR_LIST_ENUM_XrSessionState(CURVLAB_RT_STATE)
    default:
      break;
  }
#undef CURVLAB_RT_STATE
  return "XR_SESSION_STATE_" + std::to_string(static_cast<int>(s));
}

// ---- objects ---------------------------------------------------------------

struct Instance;
struct Session;
struct ActionSet;

struct Action {
  ActionSet* set = nullptr;
  std::string name;
  XrActionType type = XR_ACTION_TYPE_BOOLEAN_INPUT;
  std::vector<XrPath> subactions;
  // Per subaction (index into subactions; one slot when there are none):
  // the state reported by the last xrSyncActions.
  struct State {
    float value = 0.0f;
    bool active = false;
    bool changed = false;
    XrTime last_change = 0;
  };
  std::vector<State> states;
};

struct ActionSet {
  Instance* instance = nullptr;
  std::string name;
  std::vector<std::unique_ptr<Action>> actions;
  Session* attached_to = nullptr;
};

struct Space {
  Session* session = nullptr;
  XrReferenceSpaceType reference = XR_REFERENCE_SPACE_TYPE_MAX_ENUM;  // or an action space
  Action* action = nullptr;
  int hand = -1;
  Pose offset;
};

struct Swapchain {
  Session* session = nullptr;
  VkFormat format = VK_FORMAT_UNDEFINED;
  std::uint32_t width = 0, height = 0, array_size = 1;
  std::vector<VkImage> images;
  std::vector<VkDeviceMemory> memory;
  std::deque<std::uint32_t> acquired;  // in acquisition order
  bool waited = false;                 // the oldest acquired image was waited
  std::uint32_t next = 0;
  std::optional<std::uint32_t> last_released;
  std::int64_t acquisitions = 0;  // images acquired so far
  std::int64_t busy_until_ns = 0;  // CURVLAB_TEST_XR_SWAPCHAIN_WAIT: the compositor reads the oldest acquired image until then
};

struct VulkanDevice {
  PFN_vkGetInstanceProcAddr gipa = nullptr;
  PFN_vkGetDeviceProcAddr gdpa = nullptr;
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
#define CURVLAB_RT_DEVICE_FNS(X)                                                                   \
  X(vkGetDeviceQueue) X(vkCreateImage) X(vkDestroyImage) X(vkGetImageMemoryRequirements)        \
  X(vkAllocateMemory) X(vkFreeMemory) X(vkBindImageMemory) X(vkCreateBuffer) X(vkDestroyBuffer) \
  X(vkGetBufferMemoryRequirements) X(vkBindBufferMemory) X(vkMapMemory) X(vkUnmapMemory)        \
  X(vkCreateCommandPool) X(vkDestroyCommandPool) X(vkAllocateCommandBuffers)                     \
  X(vkBeginCommandBuffer) X(vkEndCommandBuffer) X(vkResetCommandBuffer) X(vkCmdPipelineBarrier) \
  X(vkCmdCopyImageToBuffer) X(vkQueueSubmit) X(vkCreateFence) X(vkDestroyFence)                 \
  X(vkWaitForFences) X(vkResetFences) X(vkDeviceWaitIdle)
#define CURVLAB_RT_MEMBER(name) PFN_##name name = nullptr;
  CURVLAB_RT_DEVICE_FNS(CURVLAB_RT_MEMBER)
#undef CURVLAB_RT_MEMBER
  PFN_vkGetPhysicalDeviceMemoryProperties vkGetPhysicalDeviceMemoryProperties = nullptr;
};

struct Session {
  Instance* instance = nullptr;
  XrSessionState state = XR_SESSION_STATE_UNKNOWN;
  bool running = false;
  bool exit_requested = false;
  std::int64_t lost_from_ns = -1;  // CURVLAB_TEST_XR_LOSS: frame calls fail from then on
  bool focused_once = false;
  bool faulted = false;  // the scripted fault (CURVLAB_TEST_XR_FAIL) has happened
  std::int64_t focus_t0_ns = 0;  // CLOCK_MONOTONIC when first FOCUSED
  std::vector<int> unfocus_phase;  // per scripted spell: 0 pending, 1 unfocused, 2 done
  // CURVLAB_TEST_XR_RESTART: pending, stopping (until xrEndSession), idle
  // (since idle_since_ns), ready (until the first frame ends), done.
  enum class Restart { pending, stopping, idle, ready, done } restart = Restart::pending;
  std::int64_t idle_since_ns = 0;
  // CURVLAB_TEST_XR_STATES: READY at ready_at_ns (0: sent), and the frame
  // (frames_ended) at which the last step up was taken.
  std::int64_t ready_at_ns = 0;
  std::int64_t step_frame = 0;
  // CURVLAB_TEST_XR_STAGE_MOVE: when STAGE's origin moves (0: not announced).
  XrTime stage_change = 0;
  bool events_lost_sent = false;
  XrTime last_views_logged = 0;
  bool refresh_changed = false;  // the runtime's own rate change was made
  float refresh_hz = 90.0f;      // the display's current rate
  VulkanDevice* vk = nullptr;
  VkQueue queue = VK_NULL_HANDLE;
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmd = VK_NULL_HANDLE;
  VkFence fence = VK_NULL_HANDLE;
  // Frame loop.
  bool waited = false;  // xrWaitFrame returned, xrBeginFrame not yet called
  bool begun = false;
  std::int64_t last_wake_ns = 0;
  XrTime waited_display = 0;
  XrTime begun_display = 0;
  bool waited_render = false;  // the shouldRender xrWaitFrame gave the waited frame
  bool begun_render = false;   // … and the begun one
  std::int64_t frames_waited = 0;
  std::int64_t frames_submitted = 0;
  std::vector<ActionSet*> attached;
  std::string active_profile;  // the interaction profile the controllers use ("" none)
  std::int64_t frames_ended = 0;  // successful xrEndFrame calls
  std::set<Space*> spaces;
  std::set<Swapchain*> swapchains;
};

struct EyeTracker {
  Session* session = nullptr;
};

struct Instance {
  bool timespec = false;
  bool win32_time = false;  // XR_KHR_win32_convert_performance_counter_time (Windows)
  bool refresh_rate = false;  // XR_FB_display_refresh_rate enabled
  bool eye_gaze = false;      // XR_EXT_eye_gaze_interaction enabled
  bool eye_tracking = false;  // XR_FB_eye_tracking_social enabled
  std::map<EyeTracker*, std::unique_ptr<EyeTracker>> eye_trackers;
  bool requirements_queried = false;
  Script script;
  std::deque<XrEventDataBuffer> events;
  std::vector<std::string> paths;  // XrPath n ↔ paths[n − 1]
  std::vector<std::unique_ptr<ActionSet>> sets;
  std::map<std::string, std::vector<std::pair<Action*, std::string>>> suggested;  // profile → bindings
  VulkanDevice vk;
  std::unique_ptr<Session> session;
  std::map<Space*, std::unique_ptr<Space>> spaces;
  std::map<Swapchain*, std::unique_ptr<Swapchain>> swapchains;
  std::ofstream log;
};

std::mutex g_mutex;
std::unique_ptr<Instance> g_instance;

template <class H, class T>
H handle_of(T* p) {
  return reinterpret_cast<H>(p);
}

Instance* instance_of(XrInstance h) {
  return g_instance && handle_of<XrInstance>(g_instance.get()) == h ? g_instance.get() : nullptr;
}

Session* session_of(XrSession h) {
  if (!g_instance || !g_instance->session) return nullptr;
  return handle_of<XrSession>(g_instance->session.get()) == h ? g_instance->session.get() : nullptr;
}

Space* space_of(XrSpace h) {
  if (!g_instance) return nullptr;
  auto it = g_instance->spaces.find(reinterpret_cast<Space*>(h));
  return it == g_instance->spaces.end() ? nullptr : it->second.get();
}

Swapchain* swapchain_of(XrSwapchain h) {
  if (!g_instance) return nullptr;
  auto it = g_instance->swapchains.find(reinterpret_cast<Swapchain*>(h));
  return it == g_instance->swapchains.end() ? nullptr : it->second.get();
}

ActionSet* set_of(XrActionSet h) {
  if (!g_instance) return nullptr;
  for (auto& s : g_instance->sets)
    if (handle_of<XrActionSet>(s.get()) == h) return s.get();
  return nullptr;
}

Action* action_of(XrAction h) {
  if (!g_instance) return nullptr;
  for (auto& s : g_instance->sets)
    for (auto& a : s->actions)
      if (handle_of<XrAction>(a.get()) == h) return a.get();
  return nullptr;
}

void log_line(const std::string& line) {
  if (g_instance && g_instance->log.is_open()) {
    g_instance->log << line << '\n';
    g_instance->log.flush();
  }
}

// A broken rule: the specification's error, logged.
XrResult violation(const char* function, XrResult result, const std::string& what) {
  const std::string line =
      std::string("violation ") + function + " " + result_name(result) + ": " + what;
  std::fprintf(stderr, "curvlab test runtime: %s\n", line.c_str());
  log_line(line);
  return result;
}

void warning(const char* function, const std::string& what) {
  const std::string line = std::string("warning ") + function + ": " + what;
  std::fprintf(stderr, "curvlab test runtime: %s\n", line.c_str());
  log_line(line);
}

std::string path_text(const Instance& inst, XrPath p) {
  return p >= 1 && p <= inst.paths.size() ? inst.paths[p - 1] : std::string();
}

// The XrPath of a well-formed path string, made on first use.
XrPath intern(Instance& inst, const std::string& text) {
  const auto it = std::find(inst.paths.begin(), inst.paths.end(), text);
  if (it != inst.paths.end()) return static_cast<XrPath>(it - inst.paths.begin()) + 1;
  inst.paths.push_back(text);
  return inst.paths.size();
}

// ---- session states and script ---------------------------------------------

void queue_state(Session& s, XrSessionState next) {
  XrEventDataBuffer buffer{};
  auto* e = reinterpret_cast<XrEventDataSessionStateChanged*>(&buffer);
  e->type = XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED;
  e->session = handle_of<XrSession>(&s);
  e->state = next;
  const std::int64_t now = monotonic_ns();
  e->time = to_xr(now);
  s.instance->events.push_back(buffer);
  s.state = next;
  log_line("state " + state_name(next) + " monotonic_ns " + std::to_string(now));
}

// The controllers' interaction profile changed (OpenXR 1.0 §11.4): the
// application may now ask which profile and which sources its actions use.
void queue_profile_changed(Session& s) {
  XrEventDataBuffer buffer{};
  auto* e = reinterpret_cast<XrEventDataInteractionProfileChanged*>(&buffer);
  e->type = XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED;
  e->session = handle_of<XrSession>(&s);
  s.instance->events.push_back(buffer);
}

XrPosef to_xr_pose(const Pose& p);

// The display's refresh rate changes (XR_FB_display_refresh_rate): the frame
// period from the next xrWaitFrame on, and an event where the application
// enabled the extension.
void change_refresh_rate(Session& s, float hz) {
  if (hz == s.refresh_hz) return;
  log_line("refresh_rate " + std::to_string(s.refresh_hz) + " " + std::to_string(hz));
  if (s.instance->refresh_rate) {
    XrEventDataBuffer buffer{};
    auto* e = reinterpret_cast<XrEventDataDisplayRefreshRateChangedFB*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_DISPLAY_REFRESH_RATE_CHANGED_FB;
    e->fromDisplayRefreshRate = s.refresh_hz;
    e->toDisplayRefreshRate = hz;
    s.instance->events.push_back(buffer);
  }
  s.refresh_hz = hz;
}

// The scripted events that do not change the session's state: STAGE moves,
// the event queue overflows, the runtime changes the refresh rate.
void tick_events(Session& s, double t) {
  const Script& script = s.instance->script;
  if (script.stage_move && s.stage_change == 0 && t >= script.stage_move->at_s) {
    // Announced ahead, as runtimes do: poses from changeTime on are in the
    // new origin (OpenXR 1.0 §12.4, XrEventDataReferenceSpaceChangePending).
    s.stage_change = to_xr(monotonic_ns() + 100'000'000);
    XrEventDataBuffer buffer{};
    auto* e = reinterpret_cast<XrEventDataReferenceSpaceChangePending*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING;
    e->session = handle_of<XrSession>(&s);
    e->referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
    e->changeTime = s.stage_change;
    e->poseValid = script.stage_move->pose_valid ? XR_TRUE : XR_FALSE;
    e->poseInPreviousSpace = script.stage_move->pose_valid ? to_xr_pose(script.stage_move->origin) : to_xr_pose(Pose{});
    s.instance->events.push_back(buffer);
    const Pose& o = script.stage_move->origin;
    char line[256];
    std::snprintf(line, sizeof line, "stage_move change_xr_ns %lld pose_valid %d origin %.9f %.9f %.9f %.9f %.9f %.9f %.9f",
                  static_cast<long long>(s.stage_change), script.stage_move->pose_valid ? 1 : 0, o.position_m.x,
                  o.position_m.y, o.position_m.z, o.orientation.x, o.orientation.y, o.orientation.z, o.orientation.w);
    log_line(line);
  }
  if (script.events_lost_at_s && !s.events_lost_sent && t >= *script.events_lost_at_s) {
    // The queue overflowed: the events that did not fit are gone, and the
    // next one the application polls says how many (OpenXR 1.0 §2.22).
    s.events_lost_sent = true;
    XrEventDataBuffer buffer{};
    auto* e = reinterpret_cast<XrEventDataEventsLost*>(&buffer);
    e->type = XR_TYPE_EVENT_DATA_EVENTS_LOST;
    e->lostEventCount = script.events_lost;
    s.instance->events.push_back(buffer);
    log_line("events_lost " + std::to_string(script.events_lost));
  }
  if (script.refresh.change_at_s && !s.refresh_changed && t >= *script.refresh.change_at_s) {
    s.refresh_changed = true;
    change_refresh_rate(s, script.refresh.change_to_hz);
  }
}

// Runs the script up to now: READY, focus spells and the exit request.
void tick(Session& s) {
  if (s.ready_at_ns > 0 && monotonic_ns() >= s.ready_at_ns && s.state == XR_SESSION_STATE_IDLE) {
    s.ready_at_ns = 0;
    queue_state(s, XR_SESSION_STATE_READY);
  }
  if (!s.focused_once) return;
  const Script& script = s.instance->script;
  const double t = static_cast<double>(monotonic_ns() - s.focus_t0_ns) * 1e-9;
  tick_events(s, t);
  if (script.exit_at_s && t >= *script.exit_at_s && !s.exit_requested && s.running) {
    s.exit_requested = true;
    if (s.state == XR_SESSION_STATE_FOCUSED) queue_state(s, XR_SESSION_STATE_VISIBLE);
    if (s.state == XR_SESSION_STATE_VISIBLE) queue_state(s, XR_SESSION_STATE_SYNCHRONIZED);
    queue_state(s, XR_SESSION_STATE_STOPPING);
    return;
  }
  if (script.restart && s.restart == Session::Restart::pending && t >= script.restart->at_s && s.running &&
      !s.exit_requested && s.lost_from_ns < 0) {
    s.restart = Session::Restart::stopping;
    if (s.state == XR_SESSION_STATE_FOCUSED) queue_state(s, XR_SESSION_STATE_VISIBLE);
    if (s.state == XR_SESSION_STATE_VISIBLE) queue_state(s, XR_SESSION_STATE_SYNCHRONIZED);
    queue_state(s, XR_SESSION_STATE_STOPPING);
    return;
  }
  if (s.restart == Session::Restart::idle && !s.exit_requested &&
      monotonic_ns() - s.idle_since_ns >= static_cast<std::int64_t>(script.restart->idle_s * 1e9)) {
    s.restart = Session::Restart::ready;
    queue_state(s, XR_SESSION_STATE_READY);
    return;
  }
  if (script.loss_at_s && t >= *script.loss_at_s && s.lost_from_ns < 0) {
    queue_state(s, XR_SESSION_STATE_LOSS_PENDING);
    s.lost_from_ns = monotonic_ns() + 500'000'000;
    return;
  }
  if (s.exit_requested || s.lost_from_ns >= 0) return;
  if (s.restart != Session::Restart::pending && s.restart != Session::Restart::done) return;
  for (std::size_t i = 0; i < script.unfocus.size(); ++i) {
    const Unfocus& u = script.unfocus[i];
    if (s.unfocus_phase[i] == 0 && t >= u.at_s && s.state == XR_SESSION_STATE_FOCUSED) {
      queue_state(s, XR_SESSION_STATE_VISIBLE);
      s.unfocus_phase[i] = 1;
    } else if (s.unfocus_phase[i] == 1 && t >= u.at_s + u.for_s && s.state == XR_SESSION_STATE_VISIBLE) {
      queue_state(s, XR_SESSION_STATE_FOCUSED);
      s.unfocus_phase[i] = 2;
    }
  }
}

// The scripted fault of `call`, if it is due: its result (logged once).
std::optional<XrResult> scripted_fault(Session& s, const char* call) {
  if (s.lost_from_ns >= 0 && monotonic_ns() >= s.lost_from_ns) return XR_ERROR_SESSION_LOST;
  const auto& fault = s.instance->script.fault;
  if (!fault || fault->call != call || !s.focused_once) return std::nullopt;
  const double t = static_cast<double>(monotonic_ns() - s.focus_t0_ns) * 1e-9;
  if (t < fault->at_s) return std::nullopt;
  const XrResult r = fault->result == "XR_ERROR_SESSION_LOST"    ? XR_ERROR_SESSION_LOST
                     : fault->result == "XR_ERROR_INSTANCE_LOST" ? XR_ERROR_INSTANCE_LOST
                                                                 : XR_ERROR_RUNTIME_FAILURE;
  if (!s.faulted) log_line(std::string("fault ") + call + " " + fault->result);
  s.faulted = true;
  return r;
}

// ---- Vulkan helpers ---------------------------------------------------------

std::optional<std::uint32_t> memory_type(const VulkanDevice& vk, std::uint32_t bits, VkMemoryPropertyFlags want) {
  VkPhysicalDeviceMemoryProperties props{};
  vk.vkGetPhysicalDeviceMemoryProperties(vk.physical, &props);
  for (std::uint32_t i = 0; i < props.memoryTypeCount; ++i)
    if ((bits & (1u << i)) != 0 && (props.memoryTypes[i].propertyFlags & want) == want) return i;
  return std::nullopt;
}

// Records `record` into the session's command buffer, submits it on the
// application's queue and waits. The application calls the runtime from its
// frame-loop thread, so the queue is externally synchronised as Vulkan asks.
template <class F>
bool submit_and_wait(Session& s, F record) {
  const VulkanDevice& vk = *s.vk;
  vk.vkResetCommandBuffer(s.cmd, 0);
  VkCommandBufferBeginInfo begin{};
  begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  if (vk.vkBeginCommandBuffer(s.cmd, &begin) != VK_SUCCESS) return false;
  record(s.cmd);
  if (vk.vkEndCommandBuffer(s.cmd) != VK_SUCCESS) return false;
  VkSubmitInfo submit{};
  submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
  submit.commandBufferCount = 1;
  submit.pCommandBuffers = &s.cmd;
  vk.vkResetFences(vk.device, 1, &s.fence);
  if (vk.vkQueueSubmit(s.queue, 1, &submit, s.fence) != VK_SUCCESS) return false;
  return vk.vkWaitForFences(vk.device, 1, &s.fence, VK_TRUE, UINT64_MAX) == VK_SUCCESS;
}

VkImageMemoryBarrier image_barrier(VkImage image, VkImageLayout from, VkImageLayout to, VkAccessFlags src,
                                   VkAccessFlags dst) {
  VkImageMemoryBarrier b{};
  b.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
  b.srcAccessMask = src;
  b.dstAccessMask = dst;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, VK_REMAINING_ARRAY_LAYERS};
  return b;
}

// Reads the rectangle of a released swapchain image (in
// COLOR_ATTACHMENT_OPTIMAL, as the application must leave it) back to the
// CPU, its bytes as stored (4 per texel, rows packed). The image is returned
// to COLOR_ATTACHMENT_OPTIMAL, as a compositor would after sampling it.
std::optional<std::vector<std::uint8_t>> read_back(Session& s, const Swapchain& sc, std::uint32_t index,
                                                   const XrRect2Di& rect, std::uint32_t layer) {
  const VulkanDevice& vk = *s.vk;
  const auto w = static_cast<std::uint32_t>(rect.extent.width);
  const auto h = static_cast<std::uint32_t>(rect.extent.height);
  const VkDeviceSize size = VkDeviceSize{w} * h * 4;
  VkBufferCreateInfo bi{};
  bi.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
  bi.size = size;
  bi.usage = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  VkBuffer buffer = VK_NULL_HANDLE;
  if (vk.vkCreateBuffer(vk.device, &bi, nullptr, &buffer) != VK_SUCCESS) return std::nullopt;
  VkMemoryRequirements req{};
  vk.vkGetBufferMemoryRequirements(vk.device, buffer, &req);
  const auto type = memory_type(vk, req.memoryTypeBits,
                                VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  VkDeviceMemory memory = VK_NULL_HANDLE;
  bool ok = false;
  if (type) {
    VkMemoryAllocateInfo ai{};
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = *type;
    ok = vk.vkAllocateMemory(vk.device, &ai, nullptr, &memory) == VK_SUCCESS &&
         vk.vkBindBufferMemory(vk.device, buffer, memory, 0) == VK_SUCCESS;
  }
  const VkImage image = sc.images[index];
  ok = ok && submit_and_wait(s, [&](VkCommandBuffer cb) {
         auto to_src = image_barrier(image, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL,
                                     VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                     VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT,
                                     VK_ACCESS_TRANSFER_READ_BIT);
         vk.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0,
                                 nullptr, 0, nullptr, 1, &to_src);
         VkBufferImageCopy region{};
         region.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, layer, 1};
         region.imageOffset = {rect.offset.x, rect.offset.y, 0};
         region.imageExtent = {w, h, 1};
         vk.vkCmdCopyImageToBuffer(cb, image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, buffer, 1, &region);
         auto back = image_barrier(image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL,
                                   VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, VK_ACCESS_TRANSFER_READ_BIT,
                                   VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
         vk.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TRANSFER_BIT,
                                 VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0, nullptr, 0, nullptr, 1,
                                 &back);
       });
  std::optional<std::vector<std::uint8_t>> out;
  void* mapped = nullptr;
  if (ok && vk.vkMapMemory(vk.device, memory, 0, size, 0, &mapped) == VK_SUCCESS) {
    if (mapped != nullptr) {
      out.emplace(static_cast<std::size_t>(size));
      std::memcpy(out->data(), mapped, out->size());
    }
    vk.vkUnmapMemory(vk.device, memory);
  }
  vk.vkDestroyBuffer(vk.device, buffer, nullptr);
  if (memory != VK_NULL_HANDLE) vk.vkFreeMemory(vk.device, memory, nullptr);
  return out;
}

// sRGB decoding and encoding of one channel, 0–1 (IEC 61966-2-1).
double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4); }
double srgb_encode(double l) { return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055; }

// A swapchain image read back, as linear RGBA: an sRGB image stores the
// encoded values a display shows; a UNORM image holds linear values (a
// runtime treats them as linear, XR_KHR_vulkan_enable2).
struct LinearImage {
  int width = 0, height = 0;
  std::vector<float> rgba;  // 4 per texel

  LinearImage(const std::vector<std::uint8_t>& bytes, VkFormat format, int w, int h) : width(w), height(h) {
    const bool bgra = format == VK_FORMAT_B8G8R8A8_UNORM || format == VK_FORMAT_B8G8R8A8_SRGB;
    const bool srgb = format == VK_FORMAT_R8G8B8A8_SRGB || format == VK_FORMAT_B8G8R8A8_SRGB;
    std::array<float, 256> decode{};
    for (int v = 0; v < 256; ++v)
      decode[static_cast<std::size_t>(v)] = static_cast<float>(srgb ? srgb_decode(v / 255.0) : v / 255.0);
    rgba.resize(bytes.size());
    for (std::size_t i = 0; i + 3 < bytes.size(); i += 4) {
      rgba[i + 0] = decode[bytes[i + (bgra ? 2 : 0)]];
      rgba[i + 1] = decode[bytes[i + 1]];
      rgba[i + 2] = decode[bytes[i + (bgra ? 0 : 2)]];
      rgba[i + 3] = static_cast<float>(bytes[i + 3] / 255.0);
    }
  }
  // Bilinear, clamped to the edge, at texel coordinates (x, y) (texel
  // centres at half-integers), as a compositor's sampler filters.
  [[nodiscard]] std::array<double, 4> sample(double x, double y) const {
    const double fx = std::clamp(x - 0.5, 0.0, width - 1.0);
    const double fy = std::clamp(y - 0.5, 0.0, height - 1.0);
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    const int x1 = std::min(x0 + 1, width - 1), y1 = std::min(y0 + 1, height - 1);
    const double ax = fx - x0, ay = fy - y0;
    std::array<double, 4> out{};
    for (std::size_t c = 0; c < 4; ++c) {
      auto at = [&](int u, int v) { return double(rgba[(static_cast<std::size_t>(v) * width + u) * 4 + c]); };
      out[c] = (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x1, y0)) + ay * ((1 - ax) * at(x0, y1) + ax * at(x1, y1));
    }
    return out;
  }
};

// ---- controller inputs --------------------------------------------------------

// The physical input a scripted button drives, in the active profile.
std::string input_path(const std::string& profile, const Press& p) {
  std::string input;
  if (profile == kTouch) {
    if (p.button == "trigger") input = "trigger/value";
    else if (p.button == "squeeze") input = "squeeze/value";
    else input = p.button + "/click";
  } else if (profile == kSimple) {
    if (p.button == "trigger") input = "select/click";
    else if (p.button == "menu") input = "menu/click";
    else return {};
  } else {
    return {};  // no controllers: the application suggested neither profile
  }
  return "/user/hand/" + p.hand + "/input/" + input;
}

// Value of `binding` at time t (seconds after focus), and when it last changed.
std::pair<float, std::optional<double>> input_value(const Session& s, const std::string& binding, double t) {
  float value = 0.0f;
  std::optional<double> changed;
  for (const Press& p : s.instance->script.presses) {
    // A binding to an identifier (…/input/trigger) takes the component the
    // press drives (…/input/trigger/value).
    const std::string input = input_path(s.active_profile, p);
    if (input.empty() || (input != binding && input.rfind(binding + "/", 0) != 0)) continue;
    if (held_since(p, t)) value = 1.0f;
    if (const auto c = last_change(p, t); c && (!changed || *c > *changed)) changed = c;
  }
  return {value, changed};
}

// ---- the API ------------------------------------------------------------------

bool well_formed_name(const char* name, std::size_t capacity) {
  const std::size_t n = strnlen(name, capacity);
  if (n == 0 || n == capacity) return false;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = name[i];
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.')) return false;
  }
  return true;
}

bool well_formed_path(const char* text) {
  const std::size_t n = strnlen(text, XR_MAX_PATH_LENGTH);
  if (n == 0 || n == XR_MAX_PATH_LENGTH || text[0] != '/' || text[n - 1] == '/') return false;
  for (std::size_t i = 0; i < n; ++i) {
    const char c = text[i];
    if (c == '/' && i + 1 < n && text[i + 1] == '/') return false;
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' || c == '_' || c == '.' || c == '/'))
      return false;
  }
  return true;
}

// The two-call idiom (OpenXR 1.0 §2.11, "Buffer Size Parameters"): capacity
// 0 asks for the count only; a capacity too small is
// XR_ERROR_SIZE_INSUFFICIENT with the count still written.
template <class T>
XrResult enumerate(const char* fn, const std::vector<T>& items, uint32_t capacity, uint32_t* count, T* out) {
  if (count == nullptr) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "null count output");
  *count = static_cast<uint32_t>(items.size());
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < items.size()) return XR_ERROR_SIZE_INSUFFICIENT;
  if (out == nullptr) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "null array with a capacity");
  std::copy(items.begin(), items.end(), out);
  return XR_SUCCESS;
}

// A string by the two-call idiom; the count includes the terminating null.
XrResult enumerate_string(const char* fn, const std::string& text, uint32_t capacity, uint32_t* count,
                          char* out) {
  return enumerate(fn, std::vector<char>(text.c_str(), text.c_str() + text.size() + 1), capacity, count, out);
}

// The eye-tracking extensions CURVLAB_TEST_XR_GAZE offers (none when unset
// or malformed; xrCreateInstance reports a malformed value).
std::vector<const char*> offered_eye_extensions() {
  std::string error;
  const auto gaze = read_gaze_script(error);
  std::vector<const char*> out;
  if (gaze && gaze->combined) out.push_back(XR_EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME);
  if (gaze && gaze->per_eye) out.push_back(XR_FB_EYE_TRACKING_SOCIAL_EXTENSION_NAME);
  return out;
}

XrResult XRAPI_CALL EnumerateInstanceExtensionProperties(const char* layer, uint32_t capacity, uint32_t* count,
                                                       XrExtensionProperties* props) {
  std::lock_guard lock(g_mutex);
  if (layer != nullptr && *layer != '\0')
    return violation("xrEnumerateInstanceExtensionProperties", XR_ERROR_API_LAYER_NOT_PRESENT, layer);
  // Time conversion as the platform's runtimes offer it: Windows runtimes
  // convert to the performance counter, not to timespec.
  std::vector<std::pair<const char*, uint32_t>> offered = {
      {XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME, XR_KHR_vulkan_enable2_SPEC_VERSION},
#ifdef _WIN32
      {XR_KHR_WIN32_CONVERT_PERFORMANCE_COUNTER_TIME_EXTENSION_NAME,
       XR_KHR_win32_convert_performance_counter_time_SPEC_VERSION},
#else
      {XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME, XR_KHR_convert_timespec_time_SPEC_VERSION},
#endif
      {XR_FB_DISPLAY_REFRESH_RATE_EXTENSION_NAME, XR_FB_display_refresh_rate_SPEC_VERSION}};
  for (const auto& name : offered_eye_extensions())
    offered.emplace_back(name, name == std::string(XR_EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME)
                                   ? XR_EXT_eye_gaze_interaction_SPEC_VERSION
                                   : XR_FB_eye_tracking_social_SPEC_VERSION);
  const auto n = static_cast<uint32_t>(offered.size());
  *count = n;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < n) return XR_ERROR_SIZE_INSUFFICIENT;
  for (std::size_t i = 0; i < n; ++i) {
    if (props[i].type != XR_TYPE_EXTENSION_PROPERTIES)
      return violation("xrEnumerateInstanceExtensionProperties", XR_ERROR_VALIDATION_FAILURE,
                       "XrExtensionProperties without its type");
    std::snprintf(props[i].extensionName, XR_MAX_EXTENSION_NAME_SIZE, "%s", offered[i].first);
    props[i].extensionVersion = offered[i].second;
  }
  return XR_SUCCESS;
}

// The loader answers this itself; a runtime has no layers to report.
XrResult XRAPI_CALL EnumerateApiLayerProperties(uint32_t capacity, uint32_t* count, XrApiLayerProperties* props) {
  std::lock_guard lock(g_mutex);
  return enumerate<XrApiLayerProperties>("xrEnumerateApiLayerProperties", {}, capacity, count, props);
}

XrResult XRAPI_CALL CreateInstance(const XrInstanceCreateInfo* info, XrInstance* out) {
  std::lock_guard lock(g_mutex);
  if (info == nullptr || info->type != XR_TYPE_INSTANCE_CREATE_INFO)
    return violation("xrCreateInstance", XR_ERROR_VALIDATION_FAILURE, "create info missing or untyped");
  if (g_instance) return XR_ERROR_LIMIT_REACHED;  // one instance at a time
  if (XR_VERSION_MAJOR(info->applicationInfo.apiVersion) != 1 ||
      XR_VERSION_MINOR(info->applicationInfo.apiVersion) != 0)
    return XR_ERROR_API_VERSION_UNSUPPORTED;
  if (strnlen(info->applicationInfo.applicationName, XR_MAX_APPLICATION_NAME_SIZE) == 0)
    return violation("xrCreateInstance", XR_ERROR_NAME_INVALID, "empty application name");
  auto inst = std::make_unique<Instance>();
  for (uint32_t i = 0; i < info->enabledExtensionCount; ++i) {
    const std::string e = info->enabledExtensionNames[i];
    const auto eyes = offered_eye_extensions();
    const bool offered_eyes = std::find(eyes.begin(), eyes.end(), e) != eyes.end();
#ifdef _WIN32
    if (e == XR_KHR_WIN32_CONVERT_PERFORMANCE_COUNTER_TIME_EXTENSION_NAME) inst->win32_time = true;
#else
    if (e == XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME) inst->timespec = true;
#endif
    else if (e == XR_FB_DISPLAY_REFRESH_RATE_EXTENSION_NAME) inst->refresh_rate = true;
    else if (offered_eyes && e == XR_EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME) inst->eye_gaze = true;
    else if (offered_eyes && e == XR_FB_EYE_TRACKING_SOCIAL_EXTENSION_NAME) inst->eye_tracking = true;
    else if (e != XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME) return XR_ERROR_EXTENSION_NOT_PRESENT;
  }
  std::string error;
  auto script = read_script(error);
  if (!script) {
    std::fprintf(stderr, "curvlab test runtime: %s\n", error.c_str());
    return XR_ERROR_RUNTIME_FAILURE;
  }
  inst->script = *script;
  if (!inst->script.log_path.empty()) inst->log.open(inst->script.log_path, std::ios::app);
  g_instance = std::move(inst);
  log_line(std::string("instance application ") + info->applicationInfo.applicationName + " epoch_ns " +
           std::to_string(g_epoch_ns));
  *out = handle_of<XrInstance>(g_instance.get());
  return XR_SUCCESS;
}

void destroy_swapchain(Swapchain& sc) {
  const VulkanDevice& vk = *sc.session->vk;
  vk.vkDeviceWaitIdle(vk.device);
  for (VkImage i : sc.images) vk.vkDestroyImage(vk.device, i, nullptr);
  for (VkDeviceMemory m : sc.memory) vk.vkFreeMemory(vk.device, m, nullptr);
  sc.images.clear();
  sc.memory.clear();
}

void destroy_session(Instance& inst) {
  Session& s = *inst.session;
  if (s.running) log_line("note xrDestroySession while the session is running");
  for (Swapchain* sc : s.swapchains) {
    destroy_swapchain(*sc);
    inst.swapchains.erase(sc);
  }
  for (Space* sp : s.spaces) inst.spaces.erase(sp);
  std::erase_if(inst.eye_trackers, [&s](const auto& t) { return t.second->session == &s; });
  for (auto& set : inst.sets)
    if (set->attached_to == &s) set->attached_to = nullptr;
  const VulkanDevice& vk = *s.vk;
  if (s.fence != VK_NULL_HANDLE) vk.vkDestroyFence(vk.device, s.fence, nullptr);
  if (s.pool != VK_NULL_HANDLE) vk.vkDestroyCommandPool(vk.device, s.pool, nullptr);
  // Events of the destroyed session are dropped, as the specification asks.
  inst.events.erase(std::remove_if(inst.events.begin(), inst.events.end(),
                                   [&s](const XrEventDataBuffer& e) {
                                     return (e.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED ||
                                             e.type == XR_TYPE_EVENT_DATA_INTERACTION_PROFILE_CHANGED ||
                                             e.type == XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING) &&
                                            reinterpret_cast<const XrEventDataSessionStateChanged*>(&e)
                                                    ->session == handle_of<XrSession>(&s);
                                   }),
                    inst.events.end());
  inst.session.reset();
}

XrResult XRAPI_CALL DestroyInstance(XrInstance h) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrDestroyInstance", XR_ERROR_HANDLE_INVALID, "unknown instance");
  if (inst->session) destroy_session(*inst);
  log_line("instance destroyed");
  g_instance.reset();
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetInstanceProperties(XrInstance h, XrInstanceProperties* props) {
  std::lock_guard lock(g_mutex);
  if (instance_of(h) == nullptr) return violation("xrGetInstanceProperties", XR_ERROR_HANDLE_INVALID, "");
  if (props == nullptr || props->type != XR_TYPE_INSTANCE_PROPERTIES)
    return violation("xrGetInstanceProperties", XR_ERROR_VALIDATION_FAILURE, "untyped properties");
  props->runtimeVersion = XR_MAKE_VERSION(0, 1, 0);
  std::snprintf(props->runtimeName, XR_MAX_RUNTIME_NAME_SIZE, "%s", "curvlab test runtime");
  return XR_SUCCESS;
}

XrResult XRAPI_CALL ResultToString(XrInstance h, XrResult value, char buffer[XR_MAX_RESULT_STRING_SIZE]) {
  std::lock_guard lock(g_mutex);
  if (instance_of(h) == nullptr) return violation("xrResultToString", XR_ERROR_HANDLE_INVALID, "");
  std::snprintf(buffer, XR_MAX_RESULT_STRING_SIZE, "%s", result_name(value).c_str());
  return XR_SUCCESS;
}

XrResult XRAPI_CALL StructureTypeToString(XrInstance h, XrStructureType value,
                                          char buffer[XR_MAX_STRUCTURE_NAME_SIZE]) {
  std::lock_guard lock(g_mutex);
  if (instance_of(h) == nullptr) return violation("xrStructureTypeToString", XR_ERROR_HANDLE_INVALID, "");
  std::string name = "XR_UNKNOWN_STRUCTURE_TYPE_" + std::to_string(static_cast<int>(value));
#define CURVLAB_RT_TYPE(n, v) \
  if (value == n) name = #n;
  XR_LIST_ENUM_XrStructureType(CURVLAB_RT_TYPE)
#undef CURVLAB_RT_TYPE
  std::snprintf(buffer, XR_MAX_STRUCTURE_NAME_SIZE, "%s", name.c_str());
  return XR_SUCCESS;
}

XrResult XRAPI_CALL PollEvent(XrInstance h, XrEventDataBuffer* event) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrPollEvent", XR_ERROR_HANDLE_INVALID, "");
  if (event == nullptr || event->type != XR_TYPE_EVENT_DATA_BUFFER)
    return violation("xrPollEvent", XR_ERROR_VALIDATION_FAILURE, "the buffer must be XR_TYPE_EVENT_DATA_BUFFER");
  if (inst->session) tick(*inst->session);
  if (inst->events.empty()) return XR_EVENT_UNAVAILABLE;
  *event = inst->events.front();
  inst->events.pop_front();
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetSystem(XrInstance h, const XrSystemGetInfo* info, XrSystemId* out) {
  std::lock_guard lock(g_mutex);
  if (instance_of(h) == nullptr) return violation("xrGetSystem", XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SYSTEM_GET_INFO)
    return violation("xrGetSystem", XR_ERROR_VALIDATION_FAILURE, "untyped get info");
  if (info->formFactor != XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY) return XR_ERROR_FORM_FACTOR_UNSUPPORTED;
  *out = kSystem;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetSystemProperties(XrInstance h, XrSystemId system, XrSystemProperties* props) {
  std::lock_guard lock(g_mutex);
  if (instance_of(h) == nullptr) return violation("xrGetSystemProperties", XR_ERROR_HANDLE_INVALID, "");
  if (system != kSystem) return violation("xrGetSystemProperties", XR_ERROR_SYSTEM_INVALID, "");
  if (props == nullptr || props->type != XR_TYPE_SYSTEM_PROPERTIES)
    return violation("xrGetSystemProperties", XR_ERROR_VALIDATION_FAILURE, "untyped properties");
  props->systemId = kSystem;
  props->vendorId = 0xc0de;
  std::snprintf(props->systemName, XR_MAX_SYSTEM_NAME_SIZE, "%s", "curvlab scripted headset");
  props->graphicsProperties.maxSwapchainImageWidth = kMaxSwapchainPx;
  props->graphicsProperties.maxSwapchainImageHeight = kMaxSwapchainPx;
  props->graphicsProperties.maxLayerCount = kMaxLayers;
  props->trackingProperties.orientationTracking = XR_TRUE;
  props->trackingProperties.positionTracking = XR_TRUE;
  // The eye-tracking extensions' properties, where they are enabled.
  const Instance* inst = instance_of(h);
  for (auto* n = static_cast<XrBaseOutStructure*>(props->next); n != nullptr; n = n->next) {
    if (n->type == XR_TYPE_SYSTEM_EYE_GAZE_INTERACTION_PROPERTIES_EXT && inst->eye_gaze)
      reinterpret_cast<XrSystemEyeGazeInteractionPropertiesEXT*>(n)->supportsEyeGazeInteraction = XR_TRUE;
    if (n->type == XR_TYPE_SYSTEM_EYE_TRACKING_PROPERTIES_FB && inst->eye_tracking)
      reinterpret_cast<XrSystemEyeTrackingPropertiesFB*>(n)->supportsEyeTracking = XR_TRUE;
  }
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateViewConfigurationViews(XrInstance h, XrSystemId system, XrViewConfigurationType type,
                                                    uint32_t capacity, uint32_t* count,
                                                    XrViewConfigurationView* views) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrEnumerateViewConfigurationViews", XR_ERROR_HANDLE_INVALID, "");
  if (system != kSystem) return violation("xrEnumerateViewConfigurationViews", XR_ERROR_SYSTEM_INVALID, "");
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  *count = 2;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < 2) return XR_ERROR_SIZE_INSUFFICIENT;
  for (uint32_t i = 0; i < 2; ++i) {
    if (views[i].type != XR_TYPE_VIEW_CONFIGURATION_VIEW)
      return violation("xrEnumerateViewConfigurationViews", XR_ERROR_VALIDATION_FAILURE, "untyped view");
    views[i].recommendedImageRectWidth = inst->script.eye_width_px;
    views[i].recommendedImageRectHeight = inst->script.eye_height_px;
    views[i].maxImageRectWidth = kMaxSwapchainPx;
    views[i].maxImageRectHeight = kMaxSwapchainPx;
    views[i].recommendedSwapchainSampleCount = 1;
    views[i].maxSwapchainSampleCount = 1;
  }
  return XR_SUCCESS;
}

// The instance and system checks every system query starts with.
XrResult check_system(XrInstance h, XrSystemId system, const char* fn) {
  if (instance_of(h) == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (system != kSystem) return violation(fn, XR_ERROR_SYSTEM_INVALID, std::to_string(system));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateViewConfigurations(XrInstance h, XrSystemId system, uint32_t capacity, uint32_t* count,
                                                XrViewConfigurationType* out) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrEnumerateViewConfigurations";
  if (const XrResult r = check_system(h, system, fn); XR_FAILED(r)) return r;
  return enumerate<XrViewConfigurationType>(fn, {XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO}, capacity, count, out);
}

XrResult XRAPI_CALL GetViewConfigurationProperties(XrInstance h, XrSystemId system, XrViewConfigurationType type,
                                                   XrViewConfigurationProperties* props) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetViewConfigurationProperties";
  if (const XrResult r = check_system(h, system, fn); XR_FAILED(r)) return r;
  if (props == nullptr || props->type != XR_TYPE_VIEW_CONFIGURATION_PROPERTIES)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped properties");
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  props->viewConfigurationType = type;
  props->fovMutable = XR_TRUE;  // xrEndFrame takes any field of view
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateEnvironmentBlendModes(XrInstance h, XrSystemId system, XrViewConfigurationType type,
                                                   uint32_t capacity, uint32_t* count, XrEnvironmentBlendMode* out) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrEnumerateEnvironmentBlendModes";
  if (const XrResult r = check_system(h, system, fn); XR_FAILED(r)) return r;
  if (type != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO) return XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED;
  return enumerate<XrEnvironmentBlendMode>(fn, {XR_ENVIRONMENT_BLEND_MODE_OPAQUE}, capacity, count, out);
}

// ---- XR_KHR_vulkan_enable2 ------------------------------------------------------

XrResult XRAPI_CALL GetVulkanGraphicsRequirements2(XrInstance h, XrSystemId system,
                                                   XrGraphicsRequirementsVulkan2KHR* req) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrGetVulkanGraphicsRequirements2KHR", XR_ERROR_HANDLE_INVALID, "");
  if (system != kSystem) return violation("xrGetVulkanGraphicsRequirements2KHR", XR_ERROR_SYSTEM_INVALID, "");
  if (req == nullptr || req->type != XR_TYPE_GRAPHICS_REQUIREMENTS_VULKAN2_KHR)
    return violation("xrGetVulkanGraphicsRequirements2KHR", XR_ERROR_VALIDATION_FAILURE, "untyped requirements");
  req->minApiVersionSupported = XR_MAKE_VERSION(1, 0, 0);
  req->maxApiVersionSupported = XR_MAKE_VERSION(1, 3, 0);
  inst->requirements_queried = true;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL CreateVulkanInstance(XrInstance h, const XrVulkanInstanceCreateInfoKHR* info,
                                         VkInstance* out, VkResult* vk_result) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrCreateVulkanInstanceKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_VULKAN_INSTANCE_CREATE_INFO_KHR || info->vulkanCreateInfo == nullptr ||
      info->pfnGetInstanceProcAddr == nullptr)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "create info, Vulkan create info or pfnGetInstanceProcAddr missing");
  if (info->systemId != kSystem) return violation(fn, XR_ERROR_SYSTEM_INVALID, "");
  if (!inst->requirements_queried)
    return violation(fn, XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING, "xrGetVulkanGraphicsRequirements2KHR first");
  if (info->createFlags != 0) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "createFlags must be 0");
  auto create = reinterpret_cast<PFN_vkCreateInstance>(info->pfnGetInstanceProcAddr(VK_NULL_HANDLE, "vkCreateInstance"));
  if (create == nullptr) return XR_ERROR_RUNTIME_FAILURE;
  *vk_result = create(static_cast<const VkInstanceCreateInfo*>(info->vulkanCreateInfo), nullptr, out);
  if (*vk_result == VK_SUCCESS) {
    inst->vk.gipa = info->pfnGetInstanceProcAddr;
    inst->vk.instance = *out;
  }
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetVulkanGraphicsDevice2(XrInstance h, const XrVulkanGraphicsDeviceGetInfoKHR* info,
                                             VkPhysicalDevice* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrGetVulkanGraphicsDevice2KHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_VULKAN_GRAPHICS_DEVICE_GET_INFO_KHR)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped get info");
  if (info->systemId != kSystem) return violation(fn, XR_ERROR_SYSTEM_INVALID, "");
  if (inst->vk.instance == VK_NULL_HANDLE || info->vulkanInstance != inst->vk.instance)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "not the instance made by xrCreateVulkanInstanceKHR");
  auto enumerate = reinterpret_cast<PFN_vkEnumeratePhysicalDevices>(
      inst->vk.gipa(inst->vk.instance, "vkEnumeratePhysicalDevices"));
  std::uint32_t n = 0;
  if (enumerate == nullptr || enumerate(inst->vk.instance, &n, nullptr) != VK_SUCCESS || n == 0)
    return XR_ERROR_RUNTIME_FAILURE;
  std::vector<VkPhysicalDevice> devices(n);
  if (enumerate(inst->vk.instance, &n, devices.data()) != VK_SUCCESS) return XR_ERROR_RUNTIME_FAILURE;
  // The "headset's GPU" is the first device (lavapipe on a machine without one).
  inst->vk.physical = devices.front();
  inst->vk.vkGetPhysicalDeviceMemoryProperties = reinterpret_cast<PFN_vkGetPhysicalDeviceMemoryProperties>(
      inst->vk.gipa(inst->vk.instance, "vkGetPhysicalDeviceMemoryProperties"));
  *out = inst->vk.physical;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL CreateVulkanDevice(XrInstance h, const XrVulkanDeviceCreateInfoKHR* info, VkDevice* out,
                                       VkResult* vk_result) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrCreateVulkanDeviceKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_VULKAN_DEVICE_CREATE_INFO_KHR || info->vulkanCreateInfo == nullptr ||
      info->pfnGetInstanceProcAddr == nullptr)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "create info, Vulkan create info or pfnGetInstanceProcAddr missing");
  if (info->systemId != kSystem) return violation(fn, XR_ERROR_SYSTEM_INVALID, "");
  if (info->vulkanPhysicalDevice != inst->vk.physical || inst->vk.physical == VK_NULL_HANDLE)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE,
                     "vulkanPhysicalDevice is not the one xrGetVulkanGraphicsDevice2KHR returned");
  auto create = reinterpret_cast<PFN_vkCreateDevice>(info->pfnGetInstanceProcAddr(inst->vk.instance, "vkCreateDevice"));
  if (create == nullptr) return XR_ERROR_RUNTIME_FAILURE;
  *vk_result = create(info->vulkanPhysicalDevice, static_cast<const VkDeviceCreateInfo*>(info->vulkanCreateInfo),
                      nullptr, out);
  if (*vk_result != VK_SUCCESS) return XR_SUCCESS;
  VulkanDevice& vk = inst->vk;
  vk.device = *out;
  vk.gdpa = reinterpret_cast<PFN_vkGetDeviceProcAddr>(vk.gipa(vk.instance, "vkGetDeviceProcAddr"));
#define CURVLAB_RT_LOAD(name) vk.name = reinterpret_cast<PFN_##name>(vk.gdpa(vk.device, #name));
  CURVLAB_RT_DEVICE_FNS(CURVLAB_RT_LOAD)
#undef CURVLAB_RT_LOAD
  return XR_SUCCESS;
}

// ---- session ----------------------------------------------------------------------

XrResult XRAPI_CALL CreateSession(XrInstance h, const XrSessionCreateInfo* info, XrSession* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrCreateSession";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SESSION_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  if (info->systemId != kSystem) return violation(fn, XR_ERROR_SYSTEM_INVALID, "");
  if (!inst->requirements_queried)
    return violation(fn, XR_ERROR_GRAPHICS_REQUIREMENTS_CALL_MISSING, "xrGetVulkanGraphicsRequirements2KHR first");
  if (inst->session) return XR_ERROR_LIMIT_REACHED;
  const XrGraphicsBindingVulkan2KHR* binding = nullptr;
  for (auto* n = static_cast<const XrBaseInStructure*>(info->next); n != nullptr; n = n->next)
    if (n->type == XR_TYPE_GRAPHICS_BINDING_VULKAN2_KHR) binding = reinterpret_cast<const XrGraphicsBindingVulkan2KHR*>(n);
  if (binding == nullptr) return violation(fn, XR_ERROR_GRAPHICS_DEVICE_INVALID, "no XrGraphicsBindingVulkan2KHR");
  VulkanDevice& vk = inst->vk;
  if (binding->instance != vk.instance || binding->physicalDevice != vk.physical || binding->device != vk.device ||
      vk.device == VK_NULL_HANDLE)
    return violation(fn, XR_ERROR_GRAPHICS_DEVICE_INVALID,
                     "the binding names Vulkan objects the runtime did not make (xrCreateVulkan*KHR)");
  auto s = std::make_unique<Session>();
  s->instance = inst;
  s->vk = &vk;
  s->unfocus_phase.assign(inst->script.unfocus.size(), 0);
  vk.vkGetDeviceQueue(vk.device, binding->queueFamilyIndex, binding->queueIndex, &s->queue);
  VkCommandPoolCreateInfo pi{};
  pi.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
  pi.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pi.queueFamilyIndex = binding->queueFamilyIndex;
  VkCommandBufferAllocateInfo ai{};
  ai.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkFenceCreateInfo fi{};
  fi.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
  if (s->queue == VK_NULL_HANDLE || vk.vkCreateCommandPool(vk.device, &pi, nullptr, &s->pool) != VK_SUCCESS ||
      (ai.commandPool = s->pool, vk.vkAllocateCommandBuffers(vk.device, &ai, &s->cmd) != VK_SUCCESS) ||
      vk.vkCreateFence(vk.device, &fi, nullptr, &s->fence) != VK_SUCCESS)
    return XR_ERROR_RUNTIME_FAILURE;
  inst->session = std::move(s);
  Session& session = *inst->session;
  session.refresh_hz = inst->script.refresh.start_hz;
  queue_state(session, XR_SESSION_STATE_IDLE);
  // READY at once, or as a runtime brings it once the headset is worn and
  // its compositor is up (CURVLAB_TEST_XR_STATES ready=).
  if (inst->script.bring_up.ready_s > 0.0)
    session.ready_at_ns = monotonic_ns() + static_cast<std::int64_t>(inst->script.bring_up.ready_s * 1e9);
  else
    queue_state(session, XR_SESSION_STATE_READY);
  *out = handle_of<XrSession>(&session);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL DestroySession(XrSession h) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  if (s == nullptr) return violation("xrDestroySession", XR_ERROR_HANDLE_INVALID, "");
  destroy_session(*s->instance);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL BeginSession(XrSession h, const XrSessionBeginInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrBeginSession";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SESSION_BEGIN_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped begin info");
  if (s->running) return violation(fn, XR_ERROR_SESSION_RUNNING, "already running");
  if (s->state != XR_SESSION_STATE_READY)
    return violation(fn, XR_ERROR_SESSION_NOT_READY, "state is " + state_name(s->state));
  if (info->primaryViewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return violation(fn, XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED, "");
  s->running = true;
  log_line("begin_session monotonic_ns " + std::to_string(monotonic_ns()));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EndSession(XrSession h) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrEndSession";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!s->running) return violation(fn, XR_ERROR_SESSION_NOT_RUNNING, "");
  if (s->state != XR_SESSION_STATE_STOPPING)
    return violation(fn, XR_ERROR_SESSION_NOT_STOPPING, "state is " + state_name(s->state));
  s->running = false;
  s->waited = s->begun = false;
  log_line("end_session monotonic_ns " + std::to_string(monotonic_ns()));
  queue_state(*s, XR_SESSION_STATE_IDLE);
  if (s->exit_requested) {
    queue_state(*s, XR_SESSION_STATE_EXITING);
  } else if (s->restart == Session::Restart::stopping) {
    s->restart = Session::Restart::idle;
    s->idle_since_ns = monotonic_ns();
  }
  return XR_SUCCESS;
}

XrResult XRAPI_CALL RequestExitSession(XrSession h) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  if (s == nullptr) return violation("xrRequestExitSession", XR_ERROR_HANDLE_INVALID, "");
  if (!s->running) return violation("xrRequestExitSession", XR_ERROR_SESSION_NOT_RUNNING, "");
  if (!s->exit_requested) {
    s->exit_requested = true;
    if (s->state == XR_SESSION_STATE_FOCUSED) queue_state(*s, XR_SESSION_STATE_VISIBLE);
    if (s->state == XR_SESSION_STATE_VISIBLE) queue_state(*s, XR_SESSION_STATE_SYNCHRONIZED);
    queue_state(*s, XR_SESSION_STATE_STOPPING);
  }
  return XR_SUCCESS;
}

// ---- spaces -------------------------------------------------------------------------

bool normalized(const XrQuaternionf& q) {
  const double x = q.x, y = q.y, z = q.z, w = q.w;
  const double n = x * x + y * y + z * z + w * w;
  return std::abs(n - 1.0) < 1e-3;
}

Pose to_pose(const XrPosef& p) {
  return {{p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w},
          {p.position.x, p.position.y, p.position.z}};
}

XrPosef to_xr_pose(const Pose& p) {
  XrPosef out{};
  out.orientation = {static_cast<float>(p.orientation.x), static_cast<float>(p.orientation.y),
                     static_cast<float>(p.orientation.z), static_cast<float>(p.orientation.w)};
  out.position = {static_cast<float>(p.position_m.x), static_cast<float>(p.position_m.y),
                  static_cast<float>(p.position_m.z)};
  return out;
}

XrResult XRAPI_CALL CreateReferenceSpace(XrSession h, const XrReferenceSpaceCreateInfo* info, XrSpace* out) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrCreateReferenceSpace";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_REFERENCE_SPACE_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  if (info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_VIEW &&
      info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_LOCAL &&
      info->referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE)
    return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  if (!normalized(info->poseInReferenceSpace.orientation))
    return violation(fn, XR_ERROR_POSE_INVALID, "orientation not a unit quaternion");
  auto sp = std::make_unique<Space>();
  sp->session = s;
  sp->reference = info->referenceSpaceType;
  sp->offset = to_pose(info->poseInReferenceSpace);
  Space* raw = sp.get();
  s->instance->spaces.emplace(raw, std::move(sp));
  s->spaces.insert(raw);
  *out = handle_of<XrSpace>(raw);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL CreateActionSpace(XrSession h, const XrActionSpaceCreateInfo* info, XrSpace* out) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrCreateActionSpace";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_ACTION_SPACE_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  Action* a = action_of(info->action);
  if (a == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "unknown action");
  if (a->type != XR_ACTION_TYPE_POSE_INPUT) return violation(fn, XR_ERROR_ACTION_TYPE_MISMATCH, a->name);
  int hand = -1;
  if (info->subactionPath != XR_NULL_PATH) {
    if (std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath) == a->subactions.end())
      return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "subaction path not declared by " + a->name);
    hand = path_text(*s->instance, info->subactionPath) == "/user/hand/left" ? 0 : 1;
  }
  if (!normalized(info->poseInActionSpace.orientation))
    return violation(fn, XR_ERROR_POSE_INVALID, "orientation not a unit quaternion");
  auto sp = std::make_unique<Space>();
  sp->session = s;
  sp->action = a;
  sp->hand = hand < 0 ? 1 : hand;
  sp->offset = to_pose(info->poseInActionSpace);
  Space* raw = sp.get();
  s->instance->spaces.emplace(raw, std::move(sp));
  s->spaces.insert(raw);
  *out = handle_of<XrSpace>(raw);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL DestroySpace(XrSpace h) {
  std::lock_guard lock(g_mutex);
  Space* sp = space_of(h);
  if (sp == nullptr) return violation("xrDestroySpace", XR_ERROR_HANDLE_INVALID, "");
  sp->session->spaces.erase(sp);
  sp->session->instance->spaces.erase(sp);
  return XR_SUCCESS;
}

const std::vector<XrReferenceSpaceType>& reference_spaces() {
  static const std::vector<XrReferenceSpaceType> types = {
      XR_REFERENCE_SPACE_TYPE_VIEW, XR_REFERENCE_SPACE_TYPE_LOCAL, XR_REFERENCE_SPACE_TYPE_STAGE};
  return types;
}

XrResult XRAPI_CALL EnumerateReferenceSpaces(XrSession h, uint32_t capacity, uint32_t* count,
                                             XrReferenceSpaceType* out) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrEnumerateReferenceSpaces";
  if (session_of(h) == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  return enumerate(fn, reference_spaces(), capacity, count, out);
}

// The scripted play area: 3 m wide, 2.5 m deep, centred on STAGE's origin.
XrResult XRAPI_CALL GetReferenceSpaceBoundsRect(XrSession h, XrReferenceSpaceType type, XrExtent2Df* bounds) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetReferenceSpaceBoundsRect";
  if (session_of(h) == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (bounds == nullptr) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "null bounds");
  const auto& types = reference_spaces();
  if (std::find(types.begin(), types.end(), type) == types.end()) return XR_ERROR_REFERENCE_SPACE_UNSUPPORTED;
  if (type != XR_REFERENCE_SPACE_TYPE_STAGE) {
    *bounds = {0.0f, 0.0f};
    return XR_SPACE_BOUNDS_UNAVAILABLE;
  }
  *bounds = {3.0f, 2.5f};
  return XR_SUCCESS;
}

// Whether `a` is bound to the eye gaze pose (XR_EXT_eye_gaze_interaction).
bool gaze_action(const Instance& inst, const Action* a) {
  if (!inst.eye_gaze) return false;
  const auto it = inst.suggested.find(kEyeGazeProfile);
  if (it == inst.suggested.end()) return false;
  return std::any_of(it->second.begin(), it->second.end(), [a](const auto& b) { return b.first == a; });
}

constexpr XrSpaceLocationFlags kAllValid = XR_SPACE_LOCATION_ORIENTATION_VALID_BIT |
                                           XR_SPACE_LOCATION_POSITION_VALID_BIT |
                                           XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT |
                                           XR_SPACE_LOCATION_POSITION_TRACKED_BIT;

// The location flags of a device (0 head, 1 left hand, 2 right hand) at
// time t: all set, or as the script's partial tracking has them.
XrSpaceLocationFlags device_flags(const Session& s, int device, XrTime t) {
  const Script& script = s.instance->script;
  XrSpaceLocationFlags flags = kAllValid;
  // A head with inferred position (CURVLAB_TEST_XR_HEAD=orientation_only).
  if (device == 0 && !script.head_position_tracked) flags &= ~XrSpaceLocationFlags{XR_SPACE_LOCATION_POSITION_TRACKED_BIT};
  if (!s.focused_once) return flags;
  const auto mode = tracking_mode(script, device, static_cast<double>(to_mono(t) - s.focus_t0_ns) * 1e-9);
  if (!mode) return flags;
  switch (*mode) {
    case TrackingMode::inferred:
      return XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_POSITION_VALID_BIT;
    case TrackingMode::orientation_only:
      return XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT;
    case TrackingMode::lost:
      return 0;
  }
  return flags;
}

// A space's pose in the room (the first STAGE) at time t, and its location
// flags. STAGE itself is where the runtime has put its origin at t
// (CURVLAB_TEST_XR_STAGE_MOVE); the head, hands and table never move with it.
std::pair<Pose, XrSpaceLocationFlags> stage_pose(const Space& sp, XrTime t) {
  const double ts = xr_seconds(t);
  const Session& s = *sp.session;
  Pose base;
  XrSpaceLocationFlags flags = kAllValid;
  if (sp.action != nullptr && gaze_action(*s.instance, sp.action)) {
    // The combined gaze, tracked while the application has input focus.
    const bool tracked = s.state == XR_SESSION_STATE_FOCUSED && sp.action->set->attached_to == &s;
    base = combined_gaze_pose(*s.instance->script.gaze, head_pose(ts));
    flags = tracked ? kAllValid : 0;
  } else if (sp.action != nullptr) {
    // Hands are tracked while the application has input focus and the pose
    // action is bound in the active profile.
    const bool tracked = s.state == XR_SESSION_STATE_FOCUSED && sp.action->set->attached_to == &s;
    const double since_focus_s = static_cast<double>(to_mono(t) - s.focus_t0_ns) * 1e-9;
    base = hand_pose(s.instance->script, sp.hand, ts, s.focused_once ? since_focus_s : -1.0);
    flags = tracked ? device_flags(s, sp.hand + 1, t) : 0;
  } else if (sp.reference == XR_REFERENCE_SPACE_TYPE_MAX_ENUM) {
    flags = 0;  // an action space whose action was destroyed
  } else if (sp.reference == XR_REFERENCE_SPACE_TYPE_VIEW) {
    base = head_pose(ts);
    flags = device_flags(s, 0, t);
  } else if (sp.reference == XR_REFERENCE_SPACE_TYPE_LOCAL) {
    base = {Quat{}, {0.0, 1.6, 0.85}};
  } else if (sp.reference == XR_REFERENCE_SPACE_TYPE_STAGE && s.stage_change > 0 && t >= s.stage_change) {
    base = s.instance->script.stage_move->origin;
  }
  return {compose(base, sp.offset), flags};
}

// The flags of one space located in another: valid or tracked where both are.
XrSpaceLocationFlags relative_flags(XrSpaceLocationFlags a, XrSpaceLocationFlags b) {
  XrSpaceLocationFlags out = a & b;
  // A pose is not tracked where it is not valid.
  if ((out & XR_SPACE_LOCATION_POSITION_VALID_BIT) == 0) out &= ~XrSpaceLocationFlags{XR_SPACE_LOCATION_POSITION_TRACKED_BIT};
  if ((out & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT) == 0)
    out &= ~XrSpaceLocationFlags{XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT};
  return out;
}

XrResult XRAPI_CALL LocateSpace(XrSpace space, XrSpace base, XrTime time, XrSpaceLocation* location) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrLocateSpace";
  Space* a = space_of(space);
  Space* b = space_of(base);
  if (a == nullptr || b == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "unknown space");
  if (a->session != b->session) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "spaces of two sessions");
  if (location == nullptr || location->type != XR_TYPE_SPACE_LOCATION)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped location");
  if (time <= 0) return violation(fn, XR_ERROR_TIME_INVALID, "time " + std::to_string(time));
  const auto [pa, fa] = stage_pose(*a, time);
  const auto [pb, fb] = stage_pose(*b, time);
  Pose relative = compose(inverse(pb), pa);
  location->locationFlags = a == b ? kAllValid : relative_flags(fa, fb);
  // What is not valid is not known: a runtime's numbers there mean nothing,
  // and these are far from any true pose, so an application that uses them
  // shows it.
  if ((location->locationFlags & XR_SPACE_LOCATION_POSITION_VALID_BIT) == 0) relative.position_m = {0.0, -5.0, 0.0};
  if ((location->locationFlags & XR_SPACE_LOCATION_ORIENTATION_VALID_BIT) == 0) relative.orientation = Quat{};
  location->pose = to_xr_pose(relative);
  // A chained XrSpaceVelocity must be filled: the scripted poses report none.
  for (auto* n = static_cast<XrBaseOutStructure*>(location->next); n != nullptr; n = n->next)
    if (n->type == XR_TYPE_SPACE_VELOCITY) reinterpret_cast<XrSpaceVelocity*>(n)->velocityFlags = 0;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL LocateViews(XrSession h, const XrViewLocateInfo* info, XrViewState* state, uint32_t capacity,
                                uint32_t* count, XrView* views) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrLocateViews";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_VIEW_LOCATE_INFO || state == nullptr ||
      state->type != XR_TYPE_VIEW_STATE)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped locate info or view state");
  if (info->viewConfigurationType != XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO)
    return violation(fn, XR_ERROR_VIEW_CONFIGURATION_TYPE_UNSUPPORTED, "");
  Space* base = space_of(info->space);
  if (base == nullptr || base->session != s) return violation(fn, XR_ERROR_HANDLE_INVALID, "unknown space");
  if (info->displayTime <= 0) return violation(fn, XR_ERROR_TIME_INVALID, std::to_string(info->displayTime));
  *count = 2;
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < 2) return XR_ERROR_SIZE_INSUFFICIENT;
  const Pose head = head_pose(xr_seconds(info->displayTime));
  const auto [pb, fb] = stage_pose(*base, info->displayTime);
  const Pose base_inv = inverse(pb);
  // The view-state bits have the values of the space-location bits.
  const XrSpaceLocationFlags flags = relative_flags(device_flags(*s, 0, info->displayTime), fb);
  std::string line = "views xr_ns " + std::to_string(info->displayTime);
  for (uint32_t i = 0; i < 2; ++i) {
    if (views[i].type != XR_TYPE_VIEW) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped view");
    const EyeView v = eye_view(s->instance->script, static_cast<int>(i), xr_seconds(info->displayTime));
    Pose eye = compose(base_inv, compose(head, v.pose));
    if ((flags & XR_SPACE_LOCATION_POSITION_VALID_BIT) == 0) eye.position_m = {0.0, -5.0, 0.0};
    views[i].pose = to_xr_pose(eye);
    views[i].fov = {static_cast<float>(v.fov_rad[0]), static_cast<float>(v.fov_rad[1]),
                    static_cast<float>(v.fov_rad[2]), static_cast<float>(v.fov_rad[3])};
    char part[256];
    std::snprintf(part, sizeof part, " %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f %.9f", v.pose.position_m.x,
                  v.pose.position_m.y, v.pose.position_m.z, v.pose.orientation.x, v.pose.orientation.y,
                  v.pose.orientation.z, v.pose.orientation.w, v.fov_rad[0], v.fov_rad[1], v.fov_rad[2], v.fov_rad[3]);
    line += part;
  }
  state->viewStateFlags = flags;
  // One line per display time: the views relative to the head, left then
  // right (position, quaternion x y z w, field of view l r u d).
  if (info->displayTime != s->last_views_logged) {
    s->last_views_logged = info->displayTime;
    log_line(line);
  }
  return XR_SUCCESS;
}

// ---- swapchains ---------------------------------------------------------------------

// The runtime's preference first, as real runtimes list them: sRGB, or the
// script's order (CURVLAB_TEST_XR_FORMATS).
std::vector<std::int64_t> formats(const Session& s) {
  if (!s.instance->script.formats.empty()) return s.instance->script.formats;
  return {VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B8G8R8A8_SRGB, VK_FORMAT_R8G8B8A8_UNORM, VK_FORMAT_B8G8R8A8_UNORM};
}

XrResult XRAPI_CALL EnumerateSwapchainFormats(XrSession h, uint32_t capacity, uint32_t* count, int64_t* out) {
  std::lock_guard lock(g_mutex);
  const Session* s = session_of(h);
  if (s == nullptr) return violation("xrEnumerateSwapchainFormats", XR_ERROR_HANDLE_INVALID, "");
  return enumerate<std::int64_t>("xrEnumerateSwapchainFormats", formats(*s), capacity, count, out);
}

XrResult XRAPI_CALL CreateSwapchain(XrSession h, const XrSwapchainCreateInfo* info, XrSwapchain* out) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrCreateSwapchain";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SWAPCHAIN_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  if (const auto offered = formats(*s); std::find(offered.begin(), offered.end(), info->format) == offered.end())
    return violation(fn, XR_ERROR_SWAPCHAIN_FORMAT_UNSUPPORTED, std::to_string(info->format));
  log_line("swapchain format " + std::to_string(info->format) + " " + std::to_string(info->width) + "x" +
           std::to_string(info->height));
  if (info->sampleCount != 1 || info->faceCount != 1 || info->arraySize == 0 || info->mipCount != 1 ||
      info->width == 0 || info->height == 0 || info->width > kMaxSwapchainPx || info->height > kMaxSwapchainPx)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "size, samples, faces, layers or mips out of range");
  if ((info->usageFlags & XR_SWAPCHAIN_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT) != 0)
    return violation(fn, XR_ERROR_FEATURE_UNSUPPORTED, "depth usage on a colour format");
  const VulkanDevice& vk = *s->vk;
  auto sc = std::make_unique<Swapchain>();
  sc->session = s;
  sc->format = static_cast<VkFormat>(info->format);
  sc->width = info->width;
  sc->height = info->height;
  sc->array_size = info->arraySize;
  VkImageUsageFlags usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;  // the compositor's
  if ((info->usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT) != 0) usage |= VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  if ((info->usageFlags & XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT) != 0) usage |= VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  if ((info->usageFlags & XR_SWAPCHAIN_USAGE_UNORDERED_ACCESS_BIT) != 0) usage |= VK_IMAGE_USAGE_STORAGE_BIT;
  for (std::uint32_t i = 0; i < kImagesPerSwapchain; ++i) {
    VkImageCreateInfo ii{};
    ii.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
    if ((info->usageFlags & XR_SWAPCHAIN_USAGE_MUTABLE_FORMAT_BIT) != 0) ii.flags = VK_IMAGE_CREATE_MUTABLE_FORMAT_BIT;
    ii.imageType = VK_IMAGE_TYPE_2D;
    ii.format = sc->format;
    ii.extent = {info->width, info->height, 1};
    ii.mipLevels = 1;
    ii.arrayLayers = info->arraySize;
    ii.samples = VK_SAMPLE_COUNT_1_BIT;
    ii.tiling = VK_IMAGE_TILING_OPTIMAL;
    ii.usage = usage;
    ii.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    VkImage image = VK_NULL_HANDLE;
    if (vk.vkCreateImage(vk.device, &ii, nullptr, &image) != VK_SUCCESS) {
      destroy_swapchain(*sc);
      return XR_ERROR_RUNTIME_FAILURE;
    }
    sc->images.push_back(image);
    VkMemoryRequirements req{};
    vk.vkGetImageMemoryRequirements(vk.device, image, &req);
    auto type = memory_type(vk, req.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
    if (!type) type = memory_type(vk, req.memoryTypeBits, 0);
    VkMemoryAllocateInfo ai{};
    ai.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
    ai.allocationSize = req.size;
    ai.memoryTypeIndex = type.value_or(0);
    VkDeviceMemory memory = VK_NULL_HANDLE;
    if (!type || vk.vkAllocateMemory(vk.device, &ai, nullptr, &memory) != VK_SUCCESS) {
      destroy_swapchain(*sc);
      return XR_ERROR_RUNTIME_FAILURE;
    }
    sc->memory.push_back(memory);
    if (vk.vkBindImageMemory(vk.device, image, memory, 0) != VK_SUCCESS) {
      destroy_swapchain(*sc);
      return XR_ERROR_RUNTIME_FAILURE;
    }
  }
  // Colour images are handed to the application in COLOR_ATTACHMENT_OPTIMAL
  // (XR_KHR_vulkan_enable: the layout at acquire and at release).
  if ((info->usageFlags & XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT) != 0 &&
      !submit_and_wait(*s, [&](VkCommandBuffer cb) {
        for (VkImage image : sc->images) {
          auto b = image_barrier(image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL, 0,
                                 VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT);
          vk.vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                                  VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT, 0, 0, nullptr, 0, nullptr, 1, &b);
        }
      })) {
    destroy_swapchain(*sc);
    return XR_ERROR_RUNTIME_FAILURE;
  }
  Swapchain* raw = sc.get();
  s->instance->swapchains.emplace(raw, std::move(sc));
  s->swapchains.insert(raw);
  *out = handle_of<XrSwapchain>(raw);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL DestroySwapchain(XrSwapchain h) {
  std::lock_guard lock(g_mutex);
  Swapchain* sc = swapchain_of(h);
  if (sc == nullptr) return violation("xrDestroySwapchain", XR_ERROR_HANDLE_INVALID, "");
  destroy_swapchain(*sc);
  sc->session->swapchains.erase(sc);
  sc->session->instance->swapchains.erase(sc);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateSwapchainImages(XrSwapchain h, uint32_t capacity, uint32_t* count,
                                             XrSwapchainImageBaseHeader* images) {
  std::lock_guard lock(g_mutex);
  Swapchain* sc = swapchain_of(h);
  constexpr const char* fn = "xrEnumerateSwapchainImages";
  if (sc == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  *count = static_cast<uint32_t>(sc->images.size());
  if (capacity == 0) return XR_SUCCESS;
  if (capacity < sc->images.size()) return XR_ERROR_SIZE_INSUFFICIENT;
  auto* out = reinterpret_cast<XrSwapchainImageVulkan2KHR*>(images);
  for (std::size_t i = 0; i < sc->images.size(); ++i) {
    if (out[i].type != XR_TYPE_SWAPCHAIN_IMAGE_VULKAN2_KHR)
      return violation(fn, XR_ERROR_VALIDATION_FAILURE, "images must be XrSwapchainImageVulkan2KHR");
    out[i].image = sc->images[i];
  }
  return XR_SUCCESS;
}

XrResult XRAPI_CALL AcquireSwapchainImage(XrSwapchain h, const XrSwapchainImageAcquireInfo* info, uint32_t* index) {
  std::lock_guard lock(g_mutex);
  Swapchain* sc = swapchain_of(h);
  constexpr const char* fn = "xrAcquireSwapchainImage";
  if (sc == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info != nullptr && info->type != XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped acquire info");
  if (sc->acquired.size() == sc->images.size())
    return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "every image is already acquired");
  *index = sc->next;
  sc->acquired.push_back(sc->next);
  sc->next = (sc->next + 1) % static_cast<std::uint32_t>(sc->images.size());
  // Back-pressure (CURVLAB_TEST_XR_SWAPCHAIN_WAIT): the compositor is still
  // reading this image for a while.
  const SwapchainStall& stall = sc->session->instance->script.swapchain_stall;
  if (stall.every > 0 && ++sc->acquisitions % stall.every == 0 && sc->acquired.size() == 1)
    sc->busy_until_ns = monotonic_ns() + static_cast<std::int64_t>(stall.ms * 1e6);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL WaitSwapchainImage(XrSwapchain h, const XrSwapchainImageWaitInfo* info) {
  std::unique_lock lock(g_mutex);
  Swapchain* sc = swapchain_of(h);
  constexpr const char* fn = "xrWaitSwapchainImage";
  if (sc == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped wait info");
  if (sc->acquired.empty()) return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "no image acquired");
  if (sc->waited) return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "an image is already waited and not released");
  // The image is free at once, unless the compositor still reads it
  // (CURVLAB_TEST_XR_SWAPCHAIN_WAIT): then the call waits for it, at most
  // the application's timeout (XR_TIMEOUT_EXPIRED, the image still acquired
  // and not waited: the application may wait again).
  const std::int64_t now = monotonic_ns();
  const std::int64_t busy_ns = sc->busy_until_ns - now;
  if (busy_ns > 0) {
    const bool expires = info->timeout < busy_ns;
    const std::int64_t until = expires ? now + std::max<XrDuration>(info->timeout, 0) : sc->busy_until_ns;
    log_line(std::string("swapchain_wait busy_ns ") + std::to_string(busy_ns) + " timeout_ns " +
             std::to_string(info->timeout) + (expires ? " XR_TIMEOUT_EXPIRED" : " XR_SUCCESS"));
    lock.unlock();
    timespec ts{static_cast<time_t>(until / 1'000'000'000), static_cast<long>(until % 1'000'000'000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {
    }
    lock.lock();
    if (swapchain_of(h) != sc) return XR_ERROR_HANDLE_INVALID;
    if (expires) return XR_TIMEOUT_EXPIRED;
  }
  sc->busy_until_ns = 0;
  sc->waited = true;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL ReleaseSwapchainImage(XrSwapchain h, const XrSwapchainImageReleaseInfo* info) {
  std::lock_guard lock(g_mutex);
  Swapchain* sc = swapchain_of(h);
  constexpr const char* fn = "xrReleaseSwapchainImage";
  if (sc == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info != nullptr && info->type != XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped release info");
  if (!sc->waited) return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "no image waited");
  sc->waited = false;
  sc->last_released = sc->acquired.front();
  sc->acquired.pop_front();
  return XR_SUCCESS;
}

// ---- frame loop ---------------------------------------------------------------------

XrResult XRAPI_CALL WaitFrame(XrSession h, const XrFrameWaitInfo* info, XrFrameState* state) {
  std::unique_lock lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrWaitFrame";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if ((info != nullptr && info->type != XR_TYPE_FRAME_WAIT_INFO) || state == nullptr ||
      state->type != XR_TYPE_FRAME_STATE)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped wait info or frame state");
  if (!s->running) return violation(fn, XR_ERROR_SESSION_NOT_RUNNING, "");
  // OpenXR 1.0 §10.4.2: a second xrWaitFrame blocks until the frame the
  // first one returned is begun; on the application's one frame thread a
  // real runtime would block forever.
  if (s->waited)
    return violation(fn, XR_ERROR_CALL_ORDER_INVALID,
                     "a second xrWaitFrame before xrBeginFrame (a runtime blocks it until xrBeginFrame)");
  if (const auto r = scripted_fault(*s, fn)) return *r;
  const auto period = static_cast<std::int64_t>(std::llround(1e9 / static_cast<double>(s->refresh_hz)));
  std::int64_t wake = monotonic_ns();
  if (s->frames_waited > 0) {
    // The next slot on the display's grid that has not passed.
    const std::int64_t next = s->last_wake_ns + period;
    wake = wake <= next ? next : s->last_wake_ns + ((wake - s->last_wake_ns + period - 1) / period) * period;
  }
  const Script& script = s->instance->script;
  const std::int64_t frame = s->frames_waited;
  // A missed refresh: scripted (CURVLAB_TEST_XR_LATE) or by chance
  // (CURVLAB_TEST_XR_TIMING miss=).
  const bool missed = script.late_skip.count(frame) != 0 ||
                      (frame > 0 && uniform(script.timing.seed, frame, 0) < script.timing.miss);
  if (missed) wake += period;
  const bool hidden = script.late_hidden.count(frame) != 0;
  s->last_wake_ns = wake;
  ++s->frames_waited;
  // The compositor's prediction of when the image is lit: a period after
  // the wake-up, give or take its jitter.
  const auto jitter_ns = static_cast<std::int64_t>(
      std::llround((2.0 * uniform(script.timing.seed, frame, 1) - 1.0) * script.timing.jitter_ms * 1e6));
  const std::int64_t display = wake + period + jitter_ns;
  if (missed || jitter_ns != 0)
    log_line("pacing frame " + std::to_string(frame) + " missed " + (missed ? "1" : "0") + " jitter_ns " +
             std::to_string(jitter_ns));
  // Pace in real time without holding the lock.
  lock.unlock();
#ifdef _WIN32
  // winpthreads' clock_nanosleep fails for absolute CLOCK_MONOTONIC times
  // (the loop below would spin): sleep what is left, until nothing is.
  for (std::int64_t left = wake - monotonic_ns(); left > 0; left = wake - monotonic_ns())
    std::this_thread::sleep_for(std::chrono::nanoseconds(left));
#else
  timespec until{static_cast<time_t>(wake / 1'000'000'000), static_cast<long>(wake % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, nullptr) != 0) {
  }
#endif
  lock.lock();
  if (session_of(h) != s) return XR_ERROR_SESSION_LOST;
  tick(*s);
  state->predictedDisplayTime = to_xr(display);
  state->predictedDisplayPeriod = period;
  state->shouldRender =
      !hidden && (s->state == XR_SESSION_STATE_VISIBLE || s->state == XR_SESSION_STATE_FOCUSED) ? XR_TRUE : XR_FALSE;
  s->waited = true;
  s->waited_display = state->predictedDisplayTime;
  s->waited_render = state->shouldRender == XR_TRUE;
  const Pose head = head_pose(xr_seconds(state->predictedDisplayTime));
  char line[320];
  std::snprintf(line, sizeof line, "frame %lld xr_ns %lld monotonic_ns %lld head %.9f %.9f %.9f %.9f %.9f %.9f %.9f",
                static_cast<long long>(s->frames_waited - 1), static_cast<long long>(state->predictedDisplayTime),
                static_cast<long long>(display), head.position_m.x, head.position_m.y, head.position_m.z,
                head.orientation.x, head.orientation.y, head.orientation.z, head.orientation.w);
  log_line(line);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL BeginFrame(XrSession h, const XrFrameBeginInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrBeginFrame";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info != nullptr && info->type != XR_TYPE_FRAME_BEGIN_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped begin info");
  if (!s->running) return violation(fn, XR_ERROR_SESSION_NOT_RUNNING, "");
  if (!s->waited) return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "no xrWaitFrame before it");
  s->waited = false;
  const bool discarded = s->begun;
  s->begun = true;
  s->begun_display = s->waited_display;
  s->begun_render = s->waited_render;
  if (discarded) log_line("note xrBeginFrame discarded the frame begun before");
  return discarded ? XR_FRAME_DISCARDED : XR_SUCCESS;
}

// The left eye as the compositor shows it, written as an sRGB PNG: the
// projection layer's left view, with each quad layer after it laid over it
// as that eye sees the quad. Each pixel's ray from the eye meets the quad's
// plane; the quad's image is sampled there (bilinear, in linear light) and,
// where the layer asks for it, blended by its alpha (OpenXR 1.0 §10.6).
bool capture_left(Session& s, const XrFrameEndInfo& info, const XrCompositionLayerProjection& projection,
                  const std::string& path) {
  const XrCompositionLayerProjectionView& v = projection.views[0];
  const Swapchain* eye_chain = swapchain_of(v.subImage.swapchain);
  const Space* layer_space = space_of(projection.space);
  if (eye_chain == nullptr || !eye_chain->last_released || layer_space == nullptr) return false;  // checked before
  const Swapchain& sc = *eye_chain;
  const XrRect2Di& rect = v.subImage.imageRect;
  const auto bytes = read_back(s, sc, *sc.last_released, rect, v.subImage.imageArrayIndex);
  if (!bytes) return false;
  const int w = rect.extent.width, h = rect.extent.height;
  LinearImage eye(*bytes, sc.format, w, h);
  std::vector<bool> covered(static_cast<std::size_t>(w) * h, false);
  const Pose eye_pose = compose(stage_pose(*layer_space, info.displayTime).first, to_pose(v.pose));
  const double tl = std::tan(v.fov.angleLeft), tr = std::tan(v.fov.angleRight);
  const double tu = std::tan(v.fov.angleUp), td = std::tan(v.fov.angleDown);
  for (uint32_t i = 0; i < info.layerCount; ++i) {
    if (info.layers[i]->type != XR_TYPE_COMPOSITION_LAYER_QUAD) continue;
    const auto& q = *reinterpret_cast<const XrCompositionLayerQuad*>(info.layers[i]);
    if (q.eyeVisibility == XR_EYE_VISIBILITY_RIGHT) continue;
    const Swapchain* quad_chain = swapchain_of(q.subImage.swapchain);
    const Space* quad_space = space_of(q.space);
    if (quad_chain == nullptr || !quad_chain->last_released || quad_space == nullptr) return false;  // checked before
    const XrRect2Di& qr = q.subImage.imageRect;
    const auto texels = read_back(s, *quad_chain, *quad_chain->last_released, qr, q.subImage.imageArrayIndex);
    if (!texels) return false;
    const LinearImage quad(*texels, quad_chain->format, qr.extent.width, qr.extent.height);
    const Pose quad_pose = compose(stage_pose(*quad_space, info.displayTime).first, to_pose(q.pose));
    const Pose eye_in_quad = compose(inverse(quad_pose), eye_pose);
    const bool blend = (q.layerFlags & XR_COMPOSITION_LAYER_BLEND_TEXTURE_SOURCE_ALPHA_BIT) != 0;
    const bool unpremultiplied = (q.layerFlags & XR_COMPOSITION_LAYER_UNPREMULTIPLIED_ALPHA_BIT) != 0;
    const Vec3& o = eye_in_quad.position_m;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Vec3 d = rotate(eye_in_quad.orientation,
                              Vec3{tl + (x + 0.5) / w * (tr - tl), tu - (y + 0.5) / h * (tu - td), -1.0});
        if (std::abs(d.z) < 1e-12) continue;
        const double t = -o.z / d.z;
        if (t <= 0.0) continue;
        const double u = (o.x + t * d.x) / double(q.size.width) + 0.5;
        const double vv = 0.5 - (o.y + t * d.y) / double(q.size.height);
        if (u < 0.0 || u > 1.0 || vv < 0.0 || vv > 1.0) continue;
        const auto c = quad.sample(u * quad.width, vv * quad.height);
        const std::size_t at = static_cast<std::size_t>(y) * w + x;
        float* dst = &eye.rgba[4 * at];
        const double a = blend ? c[3] : 1.0;
        for (std::size_t k = 0; k < 3; ++k)
          dst[k] = static_cast<float>((unpremultiplied || !blend ? c[k] * a : c[k]) + double(dst[k]) * (1.0 - a));
        covered[at] = true;
      }
  }
  // Pixels no quad covers keep the projection's bytes: an sRGB image's as
  // they are, a UNORM image's sRGB-encoded for the display.
  const bool bgra = sc.format == VK_FORMAT_B8G8R8A8_UNORM || sc.format == VK_FORMAT_B8G8R8A8_SRGB;
  const bool linear = sc.format == VK_FORMAT_R8G8B8A8_UNORM || sc.format == VK_FORMAT_B8G8R8A8_UNORM;
  std::array<std::uint8_t, 256> encode{};
  for (int b = 0; b < 256; ++b)
    encode[static_cast<std::size_t>(b)] =
        static_cast<std::uint8_t>(std::lround((linear ? srgb_encode(b / 255.0) : b / 255.0) * 255.0));
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * h * 3);
  for (std::size_t i = 0; i < covered.size(); ++i)
    for (std::size_t k = 0; k < 3; ++k) {
      const std::size_t from = bgra ? 2 - k : k;
      rgb[3 * i + k] = covered[i] ? static_cast<std::uint8_t>(std::lround(
                                        srgb_encode(std::clamp(double(eye.rgba[4 * i + k]), 0.0, 1.0)) * 255.0))
                                  : encode[(*bytes)[4 * i + from]];
    }
  return stbi_write_png(path.c_str(), w, h, 3, rgb.data(), w * 3) != 0;
}

// A layer's sub-image: a swapchain of this session with a released image
// and none still acquired, the rectangle inside it, an existing array layer.
// `which` begins each message ("view 0: ", "quad layer: ").
XrResult check_sub_image(const Session& s, const XrSwapchainSubImage& sub, const std::string& which) {
  constexpr const char* fn = "xrEndFrame";
  const Swapchain* sc = swapchain_of(sub.swapchain);
  if (sc == nullptr || sc->session != &s) return violation(fn, XR_ERROR_HANDLE_INVALID, which + "swapchain");
  if (!sc->last_released) return violation(fn, XR_ERROR_LAYER_INVALID, which + "its swapchain has no released image");
  if (!sc->acquired.empty())
    return violation(fn, XR_ERROR_LAYER_INVALID, which + "its swapchain still has an acquired image");
  const XrRect2Di& r = sub.imageRect;
  if (r.offset.x < 0 || r.offset.y < 0 || r.extent.width <= 0 || r.extent.height <= 0 ||
      static_cast<std::uint32_t>(r.offset.x + r.extent.width) > sc->width ||
      static_cast<std::uint32_t>(r.offset.y + r.extent.height) > sc->height)
    return violation(fn, XR_ERROR_SWAPCHAIN_RECT_INVALID, which + "rectangle outside the swapchain");
  if (sub.imageArrayIndex >= sc->array_size) return violation(fn, XR_ERROR_VALIDATION_FAILURE, which + "imageArrayIndex");
  return XR_SUCCESS;
}

// A quad layer: its space, eye visibility and sub-image, a positive size
// and a unit orientation.
XrResult check_quad(const Session& s, const XrCompositionLayerQuad& q) {
  constexpr const char* fn = "xrEndFrame";
  const Space* space = space_of(q.space);
  if (space == nullptr || space->session != &s) return violation(fn, XR_ERROR_HANDLE_INVALID, "quad layer space");
  if (q.eyeVisibility != XR_EYE_VISIBILITY_BOTH && q.eyeVisibility != XR_EYE_VISIBILITY_LEFT &&
      q.eyeVisibility != XR_EYE_VISIBILITY_RIGHT)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "quad layer eyeVisibility");
  if (const XrResult r = check_sub_image(s, q.subImage, "quad layer: "); XR_FAILED(r)) return r;
  if (!(q.size.width > 0.0f && q.size.height > 0.0f && std::isfinite(q.size.width) && std::isfinite(q.size.height)))
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "quad layer: size");
  if (!normalized(q.pose.orientation)) return violation(fn, XR_ERROR_POSE_INVALID, "quad layer: orientation");
  return XR_SUCCESS;
}

XrResult check_layer(const Session& s, const XrCompositionLayerBaseHeader* header) {
  constexpr const char* fn = "xrEndFrame";
  if (header == nullptr) return violation(fn, XR_ERROR_LAYER_INVALID, "null layer");
  if (header->type == XR_TYPE_COMPOSITION_LAYER_QUAD)
    return check_quad(s, *reinterpret_cast<const XrCompositionLayerQuad*>(header));
  if (header->type != XR_TYPE_COMPOSITION_LAYER_PROJECTION)
    return violation(fn, XR_ERROR_LAYER_INVALID, "only projection and quad layers are supported");
  const auto* layer = reinterpret_cast<const XrCompositionLayerProjection*>(header);
  const Space* space = space_of(layer->space);
  if (space == nullptr || space->session != &s) return violation(fn, XR_ERROR_HANDLE_INVALID, "layer space");
  if (layer->viewCount != 2 || layer->views == nullptr)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE,
                     "a stereo projection layer needs 2 views, got " + std::to_string(layer->viewCount));
  for (uint32_t i = 0; i < 2; ++i) {
    const XrCompositionLayerProjectionView& v = layer->views[i];
    const std::string which = "view " + std::to_string(i) + ": ";
    if (v.type != XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW)
      return violation(fn, XR_ERROR_VALIDATION_FAILURE, which + "untyped");
    if (const XrResult r = check_sub_image(s, v.subImage, which); XR_FAILED(r)) return r;
    if (!normalized(v.pose.orientation)) return violation(fn, XR_ERROR_POSE_INVALID, which + "orientation");
    if (!(v.fov.angleLeft < v.fov.angleRight && v.fov.angleDown < v.fov.angleUp))
      return violation(fn, XR_ERROR_VALIDATION_FAILURE, which + "degenerate field of view");
  }
  return XR_SUCCESS;
}

// After a frame ended in a session on its way up (the first time, or started
// again after a scripted stop, the script's clock running on): the first
// frame makes it SYNCHRONIZED, then VISIBLE and FOCUSED follow, at once or
// the script's numbers of frames later (CURVLAB_TEST_XR_STATES).
void bring_up(Session& s) {
  const bool first = !s.focused_once;
  const bool again = s.restart == Session::Restart::ready;
  if ((!first && !again) || s.exit_requested || s.lost_from_ns >= 0 || !s.running) return;
  const BringUp& b = s.instance->script.bring_up;
  if (s.state == XR_SESSION_STATE_READY) {
    queue_state(s, XR_SESSION_STATE_SYNCHRONIZED);
    s.step_frame = s.frames_ended;
  }
  if (s.state == XR_SESSION_STATE_SYNCHRONIZED && s.frames_ended - s.step_frame >= b.visible_frames) {
    queue_state(s, XR_SESSION_STATE_VISIBLE);
    s.step_frame = s.frames_ended;
  }
  if (s.state == XR_SESSION_STATE_VISIBLE && s.frames_ended - s.step_frame >= b.focused_frames) {
    queue_state(s, XR_SESSION_STATE_FOCUSED);
    if (first) {
      s.focused_once = true;
      s.focus_t0_ns = monotonic_ns();
    } else {
      s.restart = Session::Restart::done;
    }
  }
}

XrResult XRAPI_CALL EndFrame(XrSession h, const XrFrameEndInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrEndFrame";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_FRAME_END_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped end info");
  if (!s->running) return violation(fn, XR_ERROR_SESSION_NOT_RUNNING, "");
  if (!s->begun) return violation(fn, XR_ERROR_CALL_ORDER_INVALID, "no xrBeginFrame before it");
  s->begun = false;
  if (const auto r = scripted_fault(*s, fn)) return *r;
  if (info->displayTime <= 0) return violation(fn, XR_ERROR_TIME_INVALID, std::to_string(info->displayTime));
  if (info->displayTime != s->begun_display)
    warning(fn, "displayTime " + std::to_string(info->displayTime) + " is not the frame's predicted display time " +
                    std::to_string(s->begun_display));
  if (info->environmentBlendMode != XR_ENVIRONMENT_BLEND_MODE_OPAQUE)
    return violation(fn, XR_ERROR_ENVIRONMENT_BLEND_MODE_UNSUPPORTED, "");
  if (info->layerCount > kMaxLayers) return violation(fn, XR_ERROR_LAYER_LIMIT_EXCEEDED, "");
  if (info->layerCount > 0 && info->layers == nullptr)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "layers missing");
  for (uint32_t i = 0; i < info->layerCount; ++i)
    if (const XrResult r = check_layer(*s, info->layers[i]); XR_FAILED(r)) return r;
  // The left eye, as the compositor would show it: the first projection
  // layer and the quad layers over it.
  const Script& script = s->instance->script;
  if (info->layerCount > 0) {
    const std::int64_t n = s->frames_submitted++;
    const auto* first = std::find_if(info->layers, info->layers + info->layerCount, [](const auto* l) {
      return l->type == XR_TYPE_COMPOSITION_LAYER_PROJECTION;
    });
    if (!script.capture_dir.empty() && n % script.capture_every == 0 && first != info->layers + info->layerCount) {
      const auto* layer = reinterpret_cast<const XrCompositionLayerProjection*>(*first);
      const std::string path = script.capture_dir + "/left_" + std::to_string(n) + "_" +
                               std::to_string(to_mono(info->displayTime)) + ".png";
      for (uint32_t i = 0; i < info->layerCount; ++i)
        if (info->layers[i]->type == XR_TYPE_COMPOSITION_LAYER_QUAD) {
          const auto& q = *reinterpret_cast<const XrCompositionLayerQuad*>(info->layers[i]);
          const XrRect2Di& r = q.subImage.imageRect;
          log_line("quad " + path + " texels " + std::to_string(r.extent.width) + "x" +
                   std::to_string(r.extent.height) + " size_m " + std::to_string(q.size.width) + " " +
                   std::to_string(q.size.height) + " at " + std::to_string(q.pose.position.x) + " " +
                   std::to_string(q.pose.position.y) + " " + std::to_string(q.pose.position.z));
        }
      if (capture_left(*s, *info, *layer, path))
        log_line("capture " + path + " monotonic_ns " + std::to_string(to_mono(info->displayTime)));
      else
        warning(fn, "could not capture " + path);
    }
  }
  log_line("end_frame " + std::to_string(s->frames_ended++) + " layers " + std::to_string(info->layerCount) +
           " state " + state_name(s->state) + " should_render " + (s->begun_render ? "1" : "0"));
  bring_up(*s);
  return XR_SUCCESS;
}

// ---- paths and actions ----------------------------------------------------------------

XrResult XRAPI_CALL StringToPath(XrInstance h, const char* text, XrPath* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrStringToPath", XR_ERROR_HANDLE_INVALID, "");
  if (text == nullptr || !well_formed_path(text))
    return violation("xrStringToPath", XR_ERROR_PATH_FORMAT_INVALID, text == nullptr ? "null" : text);
  *out = intern(*inst, text);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL PathToString(XrInstance h, XrPath path, uint32_t capacity, uint32_t* count, char* buffer) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  if (inst == nullptr) return violation("xrPathToString", XR_ERROR_HANDLE_INVALID, "");
  const std::string text = path_text(*inst, path);
  if (text.empty()) return violation("xrPathToString", XR_ERROR_PATH_INVALID, std::to_string(path));
  return enumerate_string("xrPathToString", text, capacity, count, buffer);
}

XrResult XRAPI_CALL CreateActionSet(XrInstance h, const XrActionSetCreateInfo* info, XrActionSet* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrCreateActionSet";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_ACTION_SET_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  if (!well_formed_name(info->actionSetName, XR_MAX_ACTION_SET_NAME_SIZE))
    return violation(fn, XR_ERROR_PATH_FORMAT_INVALID, "action set name");
  if (strnlen(info->localizedActionSetName, XR_MAX_LOCALIZED_ACTION_SET_NAME_SIZE) == 0)
    return violation(fn, XR_ERROR_LOCALIZED_NAME_INVALID, "empty localized name");
  for (const auto& s : inst->sets)
    if (s->name == info->actionSetName) return violation(fn, XR_ERROR_NAME_DUPLICATED, s->name);
  auto set = std::make_unique<ActionSet>();
  set->instance = inst;
  set->name = info->actionSetName;
  *out = handle_of<XrActionSet>(set.get());
  inst->sets.push_back(std::move(set));
  return XR_SUCCESS;
}

// Before actions are destroyed: spaces made from them stay valid (the
// specification keeps action spaces alive) but no longer track, and their
// suggested bindings go.
template <class Pred>
void forget_actions(Instance& inst, Pred doomed) {
  for (auto& [raw, sp] : inst.spaces)
    if (sp->action != nullptr && doomed(sp->action)) sp->action = nullptr;
  for (auto& [profile, bindings] : inst.suggested)
    bindings.erase(std::remove_if(bindings.begin(), bindings.end(), [&](const auto& b) { return doomed(b.first); }),
                   bindings.end());
}

XrResult XRAPI_CALL DestroyActionSet(XrActionSet h) {
  std::lock_guard lock(g_mutex);
  ActionSet* set = set_of(h);
  if (set == nullptr) return violation("xrDestroyActionSet", XR_ERROR_HANDLE_INVALID, "");
  Instance& inst = *set->instance;
  forget_actions(inst, [set](const Action* a) { return a->set == set; });
  if (inst.session) {
    auto& att = inst.session->attached;
    att.erase(std::remove(att.begin(), att.end(), set), att.end());
  }
  inst.sets.erase(std::find_if(inst.sets.begin(), inst.sets.end(), [set](const auto& p) { return p.get() == set; }));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL CreateAction(XrActionSet h, const XrActionCreateInfo* info, XrAction* out) {
  std::lock_guard lock(g_mutex);
  ActionSet* set = set_of(h);
  constexpr const char* fn = "xrCreateAction";
  if (set == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_ACTION_CREATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  if (set->attached_to != nullptr) return violation(fn, XR_ERROR_ACTIONSETS_ALREADY_ATTACHED, set->name);
  if (!well_formed_name(info->actionName, XR_MAX_ACTION_NAME_SIZE))
    return violation(fn, XR_ERROR_PATH_FORMAT_INVALID, "action name");
  if (strnlen(info->localizedActionName, XR_MAX_LOCALIZED_ACTION_NAME_SIZE) == 0)
    return violation(fn, XR_ERROR_LOCALIZED_NAME_INVALID, "empty localized name");
  for (const auto& a : set->actions)
    if (a->name == info->actionName) return violation(fn, XR_ERROR_NAME_DUPLICATED, a->name);
  switch (info->actionType) {
    case XR_ACTION_TYPE_BOOLEAN_INPUT:
    case XR_ACTION_TYPE_FLOAT_INPUT:
    case XR_ACTION_TYPE_VECTOR2F_INPUT:
    case XR_ACTION_TYPE_POSE_INPUT:
    case XR_ACTION_TYPE_VIBRATION_OUTPUT:
      break;
    default:
      return violation(fn, XR_ERROR_VALIDATION_FAILURE, "action type");
  }
  auto a = std::make_unique<Action>();
  a->set = set;
  a->name = info->actionName;
  a->type = info->actionType;
  for (uint32_t i = 0; i < info->countSubactionPaths; ++i) {
    const std::string p = path_text(*set->instance, info->subactionPaths[i]);
    if (p != "/user/hand/left" && p != "/user/hand/right" && p != "/user/head" && p != "/user/gamepad")
      return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "subaction path '" + p + "'");
    if (std::find(a->subactions.begin(), a->subactions.end(), info->subactionPaths[i]) != a->subactions.end())
      return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "duplicated subaction path " + p);
    a->subactions.push_back(info->subactionPaths[i]);
  }
  a->states.resize(std::max<std::size_t>(1, a->subactions.size()));
  *out = handle_of<XrAction>(a.get());
  set->actions.push_back(std::move(a));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL DestroyAction(XrAction h) {
  std::lock_guard lock(g_mutex);
  Action* a = action_of(h);
  if (a == nullptr) return violation("xrDestroyAction", XR_ERROR_HANDLE_INVALID, "");
  forget_actions(*a->set->instance, [a](const Action* x) { return x == a; });
  auto& actions = a->set->actions;
  actions.erase(std::find_if(actions.begin(), actions.end(), [a](const auto& p) { return p.get() == a; }));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL SuggestInteractionProfileBindings(XrInstance h, const XrInteractionProfileSuggestedBinding* s) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrSuggestInteractionProfileBindings";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (s == nullptr || s->type != XR_TYPE_INTERACTION_PROFILE_SUGGESTED_BINDING || s->countSuggestedBindings == 0)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped or empty suggestion");
  const std::string profile = path_text(*inst, s->interactionProfile);
  const bool eye_profile = inst->eye_gaze && profile == kEyeGazeProfile;  // XR_EXT_eye_gaze_interaction
  if (!known_profile(profile) && !eye_profile)
    return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "unknown profile '" + profile + "'");
  std::vector<std::pair<Action*, std::string>> bindings;
  for (uint32_t i = 0; i < s->countSuggestedBindings; ++i) {
    Action* a = action_of(s->suggestedBindings[i].action);
    if (a == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "binding " + std::to_string(i) + ": action");
    if (a->set->attached_to != nullptr) return violation(fn, XR_ERROR_ACTIONSETS_ALREADY_ATTACHED, a->set->name);
    const std::string path = path_text(*inst, s->suggestedBindings[i].binding);
    if (eye_profile ? path != kEyeGazePose : !profile_has(profile, path))
      return violation(fn, XR_ERROR_PATH_UNSUPPORTED, profile + " has no input '" + path + "'");
    const bool pose_input = (path.size() > 5 && path.compare(path.size() - 5, 5, "/pose") == 0) ||
                            profile_has(profile, path + "/pose");
    if ((a->type == XR_ACTION_TYPE_POSE_INPUT) != pose_input)
      return violation(fn, XR_ERROR_PATH_UNSUPPORTED, a->name + " bound to '" + path + "': pose type mismatch");
    bindings.emplace_back(a, path);
  }
  inst->suggested[profile] = std::move(bindings);  // a later suggestion replaces an earlier one
  return XR_SUCCESS;
}

XrResult XRAPI_CALL AttachSessionActionSets(XrSession h, const XrSessionActionSetsAttachInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrAttachSessionActionSets";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO || info->countActionSets == 0)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped or empty attach info");
  if (!s->attached.empty()) return violation(fn, XR_ERROR_ACTIONSETS_ALREADY_ATTACHED, "attach only once");
  for (uint32_t i = 0; i < info->countActionSets; ++i) {
    ActionSet* set = set_of(info->actionSets[i]);
    if (set == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "action set");
    s->attached.push_back(set);
  }
  for (ActionSet* set : s->attached) set->attached_to = s;
  // The controllers the headset has: Touch if the application suggested
  // bindings for it, else the simple controller if it did, else none that
  // the application can use.
  const auto& suggested = s->instance->suggested;
  s->active_profile = suggested.count(kTouch) != 0 ? kTouch : suggested.count(kSimple) != 0 ? kSimple : "";
  log_line("profile " + (s->active_profile.empty() ? std::string("none") : s->active_profile));
  if (!s->active_profile.empty()) queue_profile_changed(*s);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL SyncActions(XrSession h, const XrActionsSyncInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrSyncActions";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_ACTIONS_SYNC_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped sync info");
  std::set<ActionSet*> active;
  for (uint32_t i = 0; i < info->countActiveActionSets; ++i) {
    ActionSet* set = set_of(info->activeActionSets[i].actionSet);
    if (set == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "action set");
    if (set->attached_to != s) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, set->name);
    active.insert(set);
  }
  tick(*s);
  const bool focused = s->state == XR_SESSION_STATE_FOCUSED;
  const std::int64_t now = monotonic_ns();
  const double t = static_cast<double>(now - s->focus_t0_ns) * 1e-9;
  static const std::vector<std::pair<Action*, std::string>> unbound;
  const auto found = s->instance->suggested.find(s->active_profile);
  const auto& bindings = found == s->instance->suggested.end() ? unbound : found->second;
  for (ActionSet* set : s->attached) {
    for (auto& a : set->actions) {
      for (std::size_t k = 0; k < a->states.size(); ++k) {
        Action::State& st = a->states[k];
        const std::string sub = a->subactions.empty() ? std::string() : path_text(*s->instance, a->subactions[k]);
        float value = 0.0f;
        std::optional<double> changed;
        bool bound = false;
        for (const auto& [action, path] : bindings) {
          if (action != a.get() || (!sub.empty() && path.rfind(sub + "/", 0) != 0)) continue;
          bound = true;
          const auto [v, c] = input_value(*s, path, t);
          value = std::max(value, v);
          if (c && (!changed || *c > *changed)) changed = c;
        }
        const bool is_active = focused && active.count(set) != 0 && bound;
        const float before = st.active ? st.value : 0.0f;
        if (a->type == XR_ACTION_TYPE_BOOLEAN_INPUT) value = value > 0.5f ? 1.0f : 0.0f;
        st.changed = is_active && st.active && value != before;
        if (!is_active) value = 0.0f;
        if (st.changed) {
          st.last_change = to_xr(s->focus_t0_ns + static_cast<std::int64_t>(std::llround(changed.value_or(t) * 1e9)));
          log_line("input " + a->name + (sub.empty() ? "" : " " + sub) + " " + std::to_string(value) +
                   " monotonic_ns " + std::to_string(to_mono(st.last_change)));
        }
        st.active = is_active;
        st.value = value;
      }
    }
  }
  log_line("sync_actions frame " + std::to_string(s->frames_waited - 1) + " focused " + (focused ? "1" : "0"));
  return focused ? XR_SUCCESS : XR_SESSION_NOT_FOCUSED;
}

// The state of (action, subaction) after the last xrSyncActions, or the
// specification's error. Without a subaction path, all of the action's
// subactions together (OpenXR 1.0 §11.5, "Reading input action state"):
// active if any is, the largest value, changed if any changed.
XrResult action_state(Session* s, const XrActionStateGetInfo* info, XrActionType want, const char* fn,
                      Action::State* out) {
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_ACTION_STATE_GET_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped get info");
  Action* a = action_of(info->action);
  if (a == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "action");
  if (a->set->attached_to != s) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, a->set->name);
  if (a->type != want) return violation(fn, XR_ERROR_ACTION_TYPE_MISMATCH, a->name);
  log_line(std::string("action_state ") + fn + " " + a->name + " frame " + std::to_string(s->frames_waited - 1) +
           " focused " + (s->state == XR_SESSION_STATE_FOCUSED ? "1" : "0"));
  if (info->subactionPath == XR_NULL_PATH) {
    Action::State any;
    for (const Action::State& st : a->states) {
      if (!st.active) continue;
      any.value = any.active ? std::max(any.value, st.value) : st.value;
      any.active = true;
      any.changed = any.changed || st.changed;
      any.last_change = std::max(any.last_change, st.last_change);
    }
    *out = any;
    return XR_SUCCESS;
  }
  const auto it = std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath);
  if (it == a->subactions.end())
    return violation(fn, XR_ERROR_PATH_UNSUPPORTED,
                     a->name + " has no subaction path " + path_text(*s->instance, info->subactionPath));
  *out = a->states[static_cast<std::size_t>(it - a->subactions.begin())];
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetActionStateBoolean(XrSession h, const XrActionStateGetInfo* info, XrActionStateBoolean* state) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetActionStateBoolean";
  Action::State st;
  if (const XrResult r = action_state(session_of(h), info, XR_ACTION_TYPE_BOOLEAN_INPUT, fn, &st); XR_FAILED(r))
    return r;
  if (state == nullptr || state->type != XR_TYPE_ACTION_STATE_BOOLEAN)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped state");
  state->currentState = st.value > 0.5f ? XR_TRUE : XR_FALSE;
  state->changedSinceLastSync = st.changed ? XR_TRUE : XR_FALSE;
  state->lastChangeTime = st.last_change;
  state->isActive = st.active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetActionStateFloat(XrSession h, const XrActionStateGetInfo* info, XrActionStateFloat* state) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetActionStateFloat";
  Action::State st;
  if (const XrResult r = action_state(session_of(h), info, XR_ACTION_TYPE_FLOAT_INPUT, fn, &st); XR_FAILED(r))
    return r;
  if (state == nullptr || state->type != XR_TYPE_ACTION_STATE_FLOAT)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped state");
  state->currentState = st.value;
  state->changedSinceLastSync = st.changed ? XR_TRUE : XR_FALSE;
  state->lastChangeTime = st.last_change;
  state->isActive = st.active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

// The scripted controllers have no thumbstick or trackpad movement: a bound
// two-axis action is active and at rest.
XrResult XRAPI_CALL GetActionStateVector2f(XrSession h, const XrActionStateGetInfo* info,
                                           XrActionStateVector2f* state) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetActionStateVector2f";
  Action::State st;
  if (const XrResult r = action_state(session_of(h), info, XR_ACTION_TYPE_VECTOR2F_INPUT, fn, &st); XR_FAILED(r))
    return r;
  if (state == nullptr || state->type != XR_TYPE_ACTION_STATE_VECTOR2F)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped state");
  state->currentState = {0.0f, 0.0f};
  state->changedSinceLastSync = XR_FALSE;
  state->lastChangeTime = st.last_change;
  state->isActive = st.active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetActionStatePose(XrSession h, const XrActionStateGetInfo* info, XrActionStatePose* state) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetActionStatePose";
  Action::State st;
  if (const XrResult r = action_state(session_of(h), info, XR_ACTION_TYPE_POSE_INPUT, fn, &st); XR_FAILED(r))
    return r;
  if (state == nullptr || state->type != XR_TYPE_ACTION_STATE_POSE)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped state");
  state->isActive = st.active ? XR_TRUE : XR_FALSE;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetCurrentInteractionProfile(XrSession h, XrPath user, XrInteractionProfileState* state) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrGetCurrentInteractionProfile";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (state == nullptr || state->type != XR_TYPE_INTERACTION_PROFILE_STATE)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped state");
  if (s->attached.empty()) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, "no action sets attached");
  const std::string path = path_text(*s->instance, user);
  if (path.empty()) return violation(fn, XR_ERROR_PATH_INVALID, std::to_string(user));
  if (!top_level_user_path(path)) return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "'" + path + "'");
  const bool hand = path == "/user/hand/left" || path == "/user/hand/right";
  state->interactionProfile =
      hand && !s->active_profile.empty() ? intern(*s->instance, s->active_profile) : XR_NULL_PATH;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateBoundSourcesForAction(XrSession h, const XrBoundSourcesForActionEnumerateInfo* info,
                                                   uint32_t capacity, uint32_t* count, XrPath* sources) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrEnumerateBoundSourcesForAction";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_BOUND_SOURCES_FOR_ACTION_ENUMERATE_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped enumerate info");
  const Action* a = action_of(info->action);
  if (a == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "action");
  if (a->set->attached_to != s) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, a->set->name);
  std::vector<XrPath> bound;
  if (const auto it = s->instance->suggested.find(s->active_profile); it != s->instance->suggested.end())
    for (const auto& [action, path] : it->second)
      if (action == a) bound.push_back(intern(*s->instance, path));
  return enumerate(fn, bound, capacity, count, sources);
}

XrResult XRAPI_CALL GetInputSourceLocalizedName(XrSession h, const XrInputSourceLocalizedNameGetInfo* info,
                                                uint32_t capacity, uint32_t* count, char* buffer) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrGetInputSourceLocalizedName";
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_INPUT_SOURCE_LOCALIZED_NAME_GET_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped get info");
  if (info->whichComponents == 0) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "whichComponents is 0");
  if (s->attached.empty()) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, "no action sets attached");
  const std::string source = path_text(*s->instance, info->sourcePath);
  if (source.empty()) return violation(fn, XR_ERROR_PATH_INVALID, std::to_string(info->sourcePath));
  if (!profile_has(s->active_profile, source))
    return violation(fn, XR_ERROR_PATH_UNSUPPORTED, "'" + source + "' is not a source of the current profile");
  const XrInputSourceLocalizedNameFlags which = info->whichComponents;
  const std::string name = localized_source_name(
      s->active_profile, source, (which & XR_INPUT_SOURCE_LOCALIZED_NAME_USER_PATH_BIT) != 0,
      (which & XR_INPUT_SOURCE_LOCALIZED_NAME_INTERACTION_PROFILE_BIT) != 0,
      (which & XR_INPUT_SOURCE_LOCALIZED_NAME_COMPONENT_BIT) != 0);
  return enumerate_string(fn, name, capacity, count, buffer);
}

// The vibration action of a haptic call, or the specification's error.
XrResult haptic_action(Session* s, const XrHapticActionInfo* info, const char* fn, const Action** out) {
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_HAPTIC_ACTION_INFO)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped haptic action info");
  const Action* a = action_of(info->action);
  if (a == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "action");
  if (a->set->attached_to != s) return violation(fn, XR_ERROR_ACTIONSET_NOT_ATTACHED, a->set->name);
  if (a->type != XR_ACTION_TYPE_VIBRATION_OUTPUT) return violation(fn, XR_ERROR_ACTION_TYPE_MISMATCH, a->name);
  if (info->subactionPath != XR_NULL_PATH &&
      std::find(a->subactions.begin(), a->subactions.end(), info->subactionPath) == a->subactions.end())
    return violation(fn, XR_ERROR_PATH_UNSUPPORTED,
                     a->name + " has no subaction path " + path_text(*s->instance, info->subactionPath));
  *out = a;
  return XR_SUCCESS;
}

// Haptics are logged ("haptic" and "haptic_stop" lines); without input focus
// they are ignored, as the specification allows.
XrResult XRAPI_CALL ApplyHapticFeedback(XrSession h, const XrHapticActionInfo* info,
                                        const XrHapticBaseHeader* feedback) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrApplyHapticFeedback";
  const Action* a = nullptr;
  if (const XrResult r = haptic_action(s, info, fn, &a); XR_FAILED(r)) return r;
  if (feedback == nullptr || feedback->type != XR_TYPE_HAPTIC_VIBRATION)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "feedback must be XrHapticVibration");
  const auto* v = reinterpret_cast<const XrHapticVibration*>(feedback);
  if (!(v->amplitude >= 0.0f && v->amplitude <= 1.0f))
    return violation(fn, XR_ERROR_VALIDATION_FAILURE,
                     "amplitude " + std::to_string(v->amplitude) + " outside [0, 1]");
  if (s->state != XR_SESSION_STATE_FOCUSED) return XR_SESSION_NOT_FOCUSED;
  log_line("haptic " + a->name + " " + path_text(*s->instance, info->subactionPath) + " duration_ns " +
           std::to_string(v->duration) + " amplitude " + std::to_string(v->amplitude));
  return XR_SUCCESS;
}

XrResult XRAPI_CALL StopHapticFeedback(XrSession h, const XrHapticActionInfo* info) {
  std::lock_guard lock(g_mutex);
  Session* s = session_of(h);
  constexpr const char* fn = "xrStopHapticFeedback";
  const Action* a = nullptr;
  if (const XrResult r = haptic_action(s, info, fn, &a); XR_FAILED(r)) return r;
  if (s->state != XR_SESSION_STATE_FOCUSED) return XR_SESSION_NOT_FOCUSED;
  log_line("haptic_stop " + a->name + " " + path_text(*s->instance, info->subactionPath));
  return XR_SUCCESS;
}

// ---- XR_KHR_convert_timespec_time ----------------------------------------------------------

XrResult XRAPI_CALL ConvertTimeToTimespecTime(XrInstance h, XrTime time, timespec* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrConvertTimeToTimespecTimeKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!inst->timespec) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  if (time <= 0) return violation(fn, XR_ERROR_TIME_INVALID, std::to_string(time));
  const std::int64_t mono = to_mono(time);
  out->tv_sec = static_cast<time_t>(mono / 1'000'000'000);
  out->tv_nsec = static_cast<long>(mono % 1'000'000'000);
  return XR_SUCCESS;
}

XrResult XRAPI_CALL ConvertTimespecTimeToTime(XrInstance h, const timespec* ts, XrTime* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrConvertTimespecTimeToTimeKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!inst->timespec) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  const XrTime t = to_xr(std::int64_t{ts->tv_sec} * 1'000'000'000 + ts->tv_nsec);
  if (t <= 0) return violation(fn, XR_ERROR_TIME_INVALID, "before the runtime's epoch");
  *out = t;
  return XR_SUCCESS;
}

#ifdef _WIN32
// ---- XR_KHR_win32_convert_performance_counter_time ----------------------------------------------

// CLOCK_MONOTONIC of winpthreads is the performance counter in nanoseconds.
std::int64_t counter_frequency() {
  LARGE_INTEGER f;
  QueryPerformanceFrequency(&f);
  return static_cast<std::int64_t>(f.QuadPart);
}

XrResult XRAPI_CALL ConvertTimeToCounter(XrInstance h, XrTime time, LARGE_INTEGER* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrConvertTimeToWin32PerformanceCounterKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!inst->win32_time) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  if (time <= 0) return violation(fn, XR_ERROR_TIME_INVALID, std::to_string(time));
  const std::int64_t mono = to_mono(time), f = counter_frequency();
  out->QuadPart = mono / 1'000'000'000 * f + mono % 1'000'000'000 * f / 1'000'000'000;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL ConvertCounterToTime(XrInstance h, const LARGE_INTEGER* counter, XrTime* out) {
  std::lock_guard lock(g_mutex);
  Instance* inst = instance_of(h);
  constexpr const char* fn = "xrConvertWin32PerformanceCounterToTimeKHR";
  if (inst == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!inst->win32_time) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  const std::int64_t c = counter->QuadPart, f = counter_frequency();
  const XrTime t = to_xr(c / f * 1'000'000'000 + c % f * 1'000'000'000 / f);
  if (t <= 0) return violation(fn, XR_ERROR_TIME_INVALID, "before the runtime's epoch");
  *out = t;
  return XR_SUCCESS;
}
#endif

// ---- XR_FB_display_refresh_rate ---------------------------------------------------------------

// The session of a refresh-rate call, or the specification's error.
XrResult refresh_session(XrSession h, const char* fn, Session** out) {
  Session* s = session_of(h);
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!s->instance->refresh_rate) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  *out = s;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL EnumerateDisplayRefreshRates(XrSession h, uint32_t capacity, uint32_t* count, float* rates) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrEnumerateDisplayRefreshRatesFB";
  Session* s = nullptr;
  if (const XrResult r = refresh_session(h, fn, &s); XR_FAILED(r)) return r;
  return enumerate(fn, s->instance->script.refresh.rates, capacity, count, rates);
}

XrResult XRAPI_CALL GetDisplayRefreshRate(XrSession h, float* rate) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetDisplayRefreshRateFB";
  Session* s = nullptr;
  if (const XrResult r = refresh_session(h, fn, &s); XR_FAILED(r)) return r;
  if (rate == nullptr) return violation(fn, XR_ERROR_VALIDATION_FAILURE, "null rate");
  *rate = s->refresh_hz;
  return XR_SUCCESS;
}

// 0 asks for the runtime's default (its starting rate); another rate must
// be one it offers. The change is at once: the next frame has its period.
XrResult XRAPI_CALL RequestDisplayRefreshRate(XrSession h, float rate) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrRequestDisplayRefreshRateFB";
  Session* s = nullptr;
  if (const XrResult r = refresh_session(h, fn, &s); XR_FAILED(r)) return r;
  const Refresh& offered = s->instance->script.refresh;
  const float hz = rate == 0.0f ? offered.start_hz : rate;
  if (std::find(offered.rates.begin(), offered.rates.end(), hz) == offered.rates.end())
    return XR_ERROR_DISPLAY_REFRESH_RATE_UNSUPPORTED_FB;
  log_line("refresh_request " + std::to_string(rate));
  change_refresh_rate(*s, hz);
  return XR_SUCCESS;
}

// ---- dispatch -------------------------------------------------------------------------------

// ---- XR_FB_eye_tracking_social ------------------------------------------------------

XrResult XRAPI_CALL CreateEyeTracker(XrSession h, const XrEyeTrackerCreateInfoFB* info, XrEyeTrackerFB* out) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrCreateEyeTrackerFB";
  Session* s = session_of(h);
  if (s == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (!s->instance->eye_tracking) return violation(fn, XR_ERROR_FUNCTION_UNSUPPORTED, "extension not enabled");
  if (info == nullptr || info->type != XR_TYPE_EYE_TRACKER_CREATE_INFO_FB || out == nullptr)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped create info");
  auto t = std::make_unique<EyeTracker>();
  t->session = s;
  EyeTracker* raw = t.get();
  s->instance->eye_trackers.emplace(raw, std::move(t));
  *out = handle_of<XrEyeTrackerFB>(raw);
  return XR_SUCCESS;
}

EyeTracker* eye_tracker_of(XrEyeTrackerFB h) {
  if (!g_instance) return nullptr;
  const auto it = g_instance->eye_trackers.find(reinterpret_cast<EyeTracker*>(h));
  return it == g_instance->eye_trackers.end() ? nullptr : it->second.get();
}

XrResult XRAPI_CALL DestroyEyeTracker(XrEyeTrackerFB h) {
  std::lock_guard lock(g_mutex);
  if (eye_tracker_of(h) == nullptr) return violation("xrDestroyEyeTrackerFB", XR_ERROR_HANDLE_INVALID, "");
  g_instance->eye_trackers.erase(reinterpret_cast<EyeTracker*>(h));
  return XR_SUCCESS;
}

// Both eyes where the script puts them, relative to the base space; valid
// while FOCUSED.
XrResult XRAPI_CALL GetEyeGazes(XrEyeTrackerFB h, const XrEyeGazesInfoFB* info, XrEyeGazesFB* gazes) {
  std::lock_guard lock(g_mutex);
  constexpr const char* fn = "xrGetEyeGazesFB";
  const EyeTracker* t = eye_tracker_of(h);
  if (t == nullptr) return violation(fn, XR_ERROR_HANDLE_INVALID, "");
  if (info == nullptr || info->type != XR_TYPE_EYE_GAZES_INFO_FB || gazes == nullptr ||
      gazes->type != XR_TYPE_EYE_GAZES_FB)
    return violation(fn, XR_ERROR_VALIDATION_FAILURE, "untyped gazes info or gazes");
  const Space* base = space_of(info->baseSpace);
  if (base == nullptr || base->session != t->session) return violation(fn, XR_ERROR_HANDLE_INVALID, "base space");
  if (info->time <= 0) return violation(fn, XR_ERROR_TIME_INVALID, std::to_string(info->time));
  const Session& s = *t->session;
  const GazeScript& script = *s.instance->script.gaze;
  const auto [pb, fb] = stage_pose(*base, info->time);
  const auto eyes = eye_gaze_poses(script, head_pose(xr_seconds(info->time)));
  const bool tracked = (fb & XR_SPACE_LOCATION_POSITION_VALID_BIT) != 0 && s.state == XR_SESSION_STATE_FOCUSED;
  for (std::size_t i = 0; i < 2; ++i) {
    gazes->gaze[i].isValid = tracked ? XR_TRUE : XR_FALSE;
    gazes->gaze[i].gazePose = to_xr_pose(compose(inverse(pb), eyes[i]));
    gazes->gaze[i].gazeConfidence = tracked ? static_cast<float>(script.confidence[i]) : 0.0f;
  }
  gazes->time = info->time;
  return XR_SUCCESS;
}

XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance h, const char* name, PFN_xrVoidFunction* function);

template <class F>
PFN_xrVoidFunction fn_ptr(F f) {
  return reinterpret_cast<PFN_xrVoidFunction>(f);
}

XrResult XRAPI_CALL GetInstanceProcAddr(XrInstance h, const char* name, PFN_xrVoidFunction* function) {
  if (name == nullptr || function == nullptr) return XR_ERROR_VALIDATION_FAILURE;
  *function = nullptr;
  const std::string n = name;
  // Without an instance only these may be asked for (specification,
  // xrGetInstanceProcAddr).
  static const std::map<std::string, PFN_xrVoidFunction> global = {
      {"xrGetInstanceProcAddr", fn_ptr(&GetInstanceProcAddr)},
      {"xrEnumerateInstanceExtensionProperties", fn_ptr(&EnumerateInstanceExtensionProperties)},
      {"xrEnumerateApiLayerProperties", fn_ptr(&EnumerateApiLayerProperties)},
      {"xrCreateInstance", fn_ptr(&CreateInstance)},
  };
  static const std::map<std::string, PFN_xrVoidFunction> table = {
      {"xrDestroyInstance", fn_ptr(&DestroyInstance)},
      {"xrGetInstanceProperties", fn_ptr(&GetInstanceProperties)},
      {"xrResultToString", fn_ptr(&ResultToString)},
      {"xrStructureTypeToString", fn_ptr(&StructureTypeToString)},
      {"xrPollEvent", fn_ptr(&PollEvent)},
      {"xrGetSystem", fn_ptr(&GetSystem)},
      {"xrGetSystemProperties", fn_ptr(&GetSystemProperties)},
      {"xrEnumerateViewConfigurationViews", fn_ptr(&EnumerateViewConfigurationViews)},
      {"xrEnumerateViewConfigurations", fn_ptr(&EnumerateViewConfigurations)},
      {"xrGetViewConfigurationProperties", fn_ptr(&GetViewConfigurationProperties)},
      {"xrEnumerateEnvironmentBlendModes", fn_ptr(&EnumerateEnvironmentBlendModes)},
      {"xrEnumerateReferenceSpaces", fn_ptr(&EnumerateReferenceSpaces)},
      {"xrGetReferenceSpaceBoundsRect", fn_ptr(&GetReferenceSpaceBoundsRect)},
      {"xrDestroyAction", fn_ptr(&DestroyAction)},
      {"xrGetCurrentInteractionProfile", fn_ptr(&GetCurrentInteractionProfile)},
      {"xrGetActionStateVector2f", fn_ptr(&GetActionStateVector2f)},
      {"xrGetActionStatePose", fn_ptr(&GetActionStatePose)},
      {"xrEnumerateBoundSourcesForAction", fn_ptr(&EnumerateBoundSourcesForAction)},
      {"xrGetInputSourceLocalizedName", fn_ptr(&GetInputSourceLocalizedName)},
      {"xrApplyHapticFeedback", fn_ptr(&ApplyHapticFeedback)},
      {"xrStopHapticFeedback", fn_ptr(&StopHapticFeedback)},
      {"xrGetVulkanGraphicsRequirements2KHR", fn_ptr(&GetVulkanGraphicsRequirements2)},
      {"xrCreateVulkanInstanceKHR", fn_ptr(&CreateVulkanInstance)},
      {"xrGetVulkanGraphicsDevice2KHR", fn_ptr(&GetVulkanGraphicsDevice2)},
      {"xrCreateVulkanDeviceKHR", fn_ptr(&CreateVulkanDevice)},
      {"xrCreateSession", fn_ptr(&CreateSession)},
      {"xrDestroySession", fn_ptr(&DestroySession)},
      {"xrBeginSession", fn_ptr(&BeginSession)},
      {"xrEndSession", fn_ptr(&EndSession)},
      {"xrRequestExitSession", fn_ptr(&RequestExitSession)},
      {"xrCreateReferenceSpace", fn_ptr(&CreateReferenceSpace)},
      {"xrCreateActionSpace", fn_ptr(&CreateActionSpace)},
      {"xrDestroySpace", fn_ptr(&DestroySpace)},
      {"xrLocateSpace", fn_ptr(&LocateSpace)},
      {"xrLocateViews", fn_ptr(&LocateViews)},
      {"xrEnumerateSwapchainFormats", fn_ptr(&EnumerateSwapchainFormats)},
      {"xrCreateSwapchain", fn_ptr(&CreateSwapchain)},
      {"xrDestroySwapchain", fn_ptr(&DestroySwapchain)},
      {"xrEnumerateSwapchainImages", fn_ptr(&EnumerateSwapchainImages)},
      {"xrAcquireSwapchainImage", fn_ptr(&AcquireSwapchainImage)},
      {"xrWaitSwapchainImage", fn_ptr(&WaitSwapchainImage)},
      {"xrReleaseSwapchainImage", fn_ptr(&ReleaseSwapchainImage)},
      {"xrWaitFrame", fn_ptr(&WaitFrame)},
      {"xrBeginFrame", fn_ptr(&BeginFrame)},
      {"xrEndFrame", fn_ptr(&EndFrame)},
      {"xrStringToPath", fn_ptr(&StringToPath)},
      {"xrPathToString", fn_ptr(&PathToString)},
      {"xrCreateActionSet", fn_ptr(&CreateActionSet)},
      {"xrDestroyActionSet", fn_ptr(&DestroyActionSet)},
      {"xrCreateAction", fn_ptr(&CreateAction)},
      {"xrSuggestInteractionProfileBindings", fn_ptr(&SuggestInteractionProfileBindings)},
      {"xrAttachSessionActionSets", fn_ptr(&AttachSessionActionSets)},
      {"xrSyncActions", fn_ptr(&SyncActions)},
      {"xrGetActionStateBoolean", fn_ptr(&GetActionStateBoolean)},
      {"xrGetActionStateFloat", fn_ptr(&GetActionStateFloat)},
      {"xrConvertTimeToTimespecTimeKHR", fn_ptr(&ConvertTimeToTimespecTime)},
#ifdef _WIN32
      {"xrConvertTimeToWin32PerformanceCounterKHR", fn_ptr(&ConvertTimeToCounter)},
      {"xrConvertWin32PerformanceCounterToTimeKHR", fn_ptr(&ConvertCounterToTime)},
#endif
      {"xrConvertTimespecTimeToTimeKHR", fn_ptr(&ConvertTimespecTimeToTime)},
      {"xrEnumerateDisplayRefreshRatesFB", fn_ptr(&EnumerateDisplayRefreshRates)},
      {"xrGetDisplayRefreshRateFB", fn_ptr(&GetDisplayRefreshRate)},
      {"xrRequestDisplayRefreshRateFB", fn_ptr(&RequestDisplayRefreshRate)},
  };
  if (const auto it = global.find(n); it != global.end()) {
    *function = it->second;
    return XR_SUCCESS;
  }
  if (h == XR_NULL_HANDLE) return XR_ERROR_HANDLE_INVALID;
  {
    std::lock_guard lock(g_mutex);
    const Instance* inst = instance_of(h);
    if (inst == nullptr) return XR_ERROR_HANDLE_INVALID;
    // An extension's functions only where it was enabled.
    if (!inst->refresh_rate && n.size() > 2 && n.compare(n.size() - 2, 2, "FB") == 0)
      return XR_ERROR_FUNCTION_UNSUPPORTED;
  }
  static const std::map<std::string, PFN_xrVoidFunction> eye_tracking = {
      {"xrCreateEyeTrackerFB", fn_ptr(&CreateEyeTracker)},
      {"xrDestroyEyeTrackerFB", fn_ptr(&DestroyEyeTracker)},
      {"xrGetEyeGazesFB", fn_ptr(&GetEyeGazes)},
  };
  if (const auto e = eye_tracking.find(n); e != eye_tracking.end()) {
    std::lock_guard lock(g_mutex);
    const Instance* inst = instance_of(h);
    if (inst == nullptr || !inst->eye_tracking) return XR_ERROR_FUNCTION_UNSUPPORTED;
    *function = e->second;
    return XR_SUCCESS;
  }
  const auto it = table.find(n);
  if (it == table.end()) return XR_ERROR_FUNCTION_UNSUPPORTED;
  *function = it->second;
  return XR_SUCCESS;
}

}  // namespace
}  // namespace curvlab::test_runtime

extern "C" XrResult xrNegotiateLoaderRuntimeInterface(const XrNegotiateLoaderInfo* loaderInfo,
                                                      XrNegotiateRuntimeRequest* runtimeRequest) {
  using namespace curvlab::test_runtime;
  if (loaderInfo == nullptr || runtimeRequest == nullptr ||
      loaderInfo->structType != XR_LOADER_INTERFACE_STRUCT_LOADER_INFO ||
      loaderInfo->structVersion != kLoaderInfoVersion || loaderInfo->structSize != sizeof(XrNegotiateLoaderInfo) ||
      runtimeRequest->structType != XR_LOADER_INTERFACE_STRUCT_RUNTIME_REQUEST ||
      runtimeRequest->structVersion != kRuntimeRequestVersion ||
      runtimeRequest->structSize != sizeof(XrNegotiateRuntimeRequest))
    return XR_ERROR_INITIALIZATION_FAILED;
  if (loaderInfo->minInterfaceVersion > kRuntimeInterfaceVersion ||
      loaderInfo->maxInterfaceVersion < kRuntimeInterfaceVersion ||
      loaderInfo->minApiVersion > XR_CURRENT_API_VERSION ||
      XR_VERSION_MAJOR(loaderInfo->maxApiVersion) < 1)
    return XR_ERROR_INITIALIZATION_FAILED;
  runtimeRequest->runtimeInterfaceVersion = kRuntimeInterfaceVersion;
  runtimeRequest->runtimeApiVersion = XR_CURRENT_API_VERSION;
  runtimeRequest->getInstanceProcAddr = &GetInstanceProcAddr;
  return XR_SUCCESS;
}
