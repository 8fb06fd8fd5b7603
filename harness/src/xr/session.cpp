// The headset's OpenXR session (xr/session.hpp). The order of the calls
// follows the OpenXR specification's lifecycle: instance → system → graphics
// requirements → Vulkan instance and device made by the runtime
// (XR_KHR_vulkan_enable2) → session.
#include "curvlab/harness/xr/session.hpp"

#include "platform.hpp"
#include "runtime_vulkan.hpp"

#include "curvlab/harness/io/frame.hpp"

#include <algorithm>
#include <iostream>
#include <limits>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;
using harness::io::DeviceFailure;
using harness::io::Signal;

namespace {

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

}  // namespace

// The instance extensions curvlab asks for besides XR_KHR_vulkan_enable2,
// where the runtime offers them.
struct Session::Extensions {
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

  // The extension list comes from the runtime: without one, this is where
  // XR_ERROR_RUNTIME_UNAVAILABLE shows, before anything is created.
  static Result<Extensions> offered() {
    auto offered = available_extensions();
    if (!offered) return offered.error();
    const auto& names = offered.value();
    auto has = [&names](const char* n) { return std::find(names.begin(), names.end(), n) != names.end(); };
    if (!has(XR_KHR_VULKAN_ENABLE2_EXTENSION_NAME))
      return failure_of(XR_ERROR_EXTENSION_NOT_PRESENT, "xrEnumerateInstanceExtensionProperties");
#ifdef _WIN32
    const bool win32_time = has(XR_KHR_WIN32_CONVERT_PERFORMANCE_COUNTER_TIME_EXTENSION_NAME);
#else
    const bool win32_time = false;
#endif
    return Extensions{.timespec = has(XR_KHR_CONVERT_TIMESPEC_TIME_EXTENSION_NAME),
                      .win32_time = win32_time,
                      .refresh = has(XR_FB_DISPLAY_REFRESH_RATE_EXTENSION_NAME),
                      .gaze = gaze_extensions_in(names)};
  }
};

Session::Session(Instance instance, const harness::io::Clock& clock) : instance_(std::move(instance)), clock_(&clock) {}

Result<std::unique_ptr<Session>> Session::create(const SessionOptions& options) {
  if (options.clock == nullptr)
    return Error{Error::Kind::usage, "the OpenXR session needs the session clock (SessionOptions::clock)"};
  auto offered = Extensions::offered();
  if (!offered) return offered.error();
  auto made = Instance::create(options.application_name, offered->names());
  if (!made) return made.error();
  std::unique_ptr<Session> s(new Session(std::move(made).value(), *options.clock));
  if (auto opened = s->open(offered.value()); !opened) return opened.error();
  return s;
}

Result<Done> Session::open(const Extensions& offered) {
  const XrInstance xr = instance_.handle();
  if (offered.timespec && XR_FAILED(load(xr, "xrConvertTimeToTimespecTimeKHR", to_timespec_)))
    to_timespec_ = nullptr;
#ifdef _WIN32
  if (!offered.timespec && offered.win32_time &&
      XR_FAILED(load(xr, "xrConvertTimeToWin32PerformanceCounterKHR", to_counter_)))
    to_counter_ = nullptr;
#endif
  refresh_extension_ = offered.refresh;
  gaze_ = offered.gaze;
  auto system = instance_.hmd_system();
  if (!system) return system.error();
  system_ = system.value();
  auto vulkan = load_vulkan_enable2(xr, system_);
  if (!vulkan) return vulkan.error();
  if (auto r = check_vulkan_version(vulkan.value()); !r) return r;
  auto ctx = runtime_made_context(vulkan.value());
  if (!ctx) return ctx.error();
  context_ = std::make_unique<renderer::Context>(std::move(ctx).value());

  auto binding = graphics_binding(*context_);
  auto session_info = tagged<XrSessionCreateInfo>(XR_TYPE_SESSION_CREATE_INFO);
  session_info.next = &binding;
  session_info.systemId = system_;
  if (const XrResult r = xrCreateSession(xr, &session_info, session_.out()); XR_FAILED(r))
    return failure_of(r, "xrCreateSession");
  return Done{};
}

// The parts are gone by now (they are destroyed first); the session handle
// goes before the Vulkan device it was made with (the members' order).
Session::~Session() = default;

void Session::join(SessionPart& part) { parts_.push_back(&part); }

void Session::leave(SessionPart& part) { std::erase(parts_, &part); }

void Session::fail(XrResult r, const char* call) {
  failed_ = true;
  throw DeviceFailure(call, result_name(r));
}

bool Session::request_exit() {
  if (const XrResult r = xrRequestExitSession(session_.get()); XR_FAILED(r)) {
    std::cerr << "curvlab: xr: " << failure_of(r, "xrRequestExitSession").message << '\n';
    return false;
  }
  leaving_ = true;
  return true;
}

void Session::on_state(SessionState next) {
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
    if (frame_begun_) (void)end_frame({});  // the session is ending: only xrEndSession counts
    if (const XrResult r = xrEndSession(session_.get()); XR_FAILED(r))
      std::cerr << "curvlab: xr: " << failure_of(r, "xrEndSession").message << '\n';
  }
  if (u.mode != RunMode::Running && before == RunMode::Running) {
    // Inactive while unfocused; the return syncs afresh.
    for (SessionPart* p : parts_) p->on_focus_lost();
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

bool Session::poll_events() {
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
      case XR_TYPE_EVENT_DATA_EVENTS_LOST:
        on_events_lost(*reinterpret_cast<const XrEventDataEventsLost*>(&event));
        break;
      default:
        // The parts' own: a STAGE move (tracked poses), a refresh-rate
        // change (the display).
        for (SessionPart* p : parts_) p->on_event(event);
        break;
    }
  }
  return !failed_ && state_.mode() != RunMode::Exit;
}

// The runtime's queue overflowed and dropped events (OpenXR 1.0 §2.22).
// Nothing says which; the session states that matter come again with the
// next change, so the session goes on, and the loss is data.
void Session::on_events_lost(const XrEventDataEventsLost& e) {
  std::cerr << "curvlab: xr: the OpenXR runtime dropped " << e.lostEventCount
            << " event(s) it could not queue; the session goes on (recorded as an events_lost event)\n";
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::events_lost;
  report.lost_events = e.lostEventCount;
  reports_.push_back(report);
}

Signal Session::next_signal() {
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

void Session::take_reports(std::vector<harness::io::DisplayReport>& out) {
  out.insert(out.end(), reports_.begin(), reports_.end());
  reports_.clear();
}

XrResult Session::wait_frame() {
  auto wait_info = tagged<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
  frame_state_ = tagged<XrFrameState>(XR_TYPE_FRAME_STATE);
  return xrWaitFrame(session_.get(), &wait_info, &frame_state_);
}

XrResult Session::begin_frame() {
  auto begin_info = tagged<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
  const XrResult r = xrBeginFrame(session_.get(), &begin_info);
  if (XR_SUCCEEDED(r)) frame_begun_ = true;
  return r;
}

XrResult Session::end_frame(const std::vector<const XrCompositionLayerBaseHeader*>& layers) {
  auto info = tagged<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
  info.displayTime = frame_state_.predictedDisplayTime;
  info.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
  info.layerCount = static_cast<std::uint32_t>(layers.size());
  info.layers = layers.empty() ? nullptr : layers.data();
  frame_begun_ = false;
  ++frames_ended_;
  return xrEndFrame(session_.get(), &info);
}

void Session::frame_began(std::int64_t now_ns) {
  // Without XR_KHR_convert_timespec_time: the first frame's image is taken
  // to appear one period after xrWaitFrame returned (docs/lab.md).
  if (to_timespec_ == nullptr && !clock_map_.anchored())
    clock_map_.anchor(frame_state_.predictedDisplayTime, now_ns + frame_state_.predictedDisplayPeriod);
  synced_ = false;
  if (state_.mode() == RunMode::Running) sync_actions();
}

Result<Done> Session::attach(const std::vector<XrActionSet>& sets) {
  auto attach = tagged<XrSessionActionSetsAttachInfo>(XR_TYPE_SESSION_ACTION_SETS_ATTACH_INFO);
  attach.countActionSets = static_cast<std::uint32_t>(sets.size());
  attach.actionSets = sets.data();
  if (const XrResult r = xrAttachSessionActionSets(session_.get(), &attach); XR_FAILED(r))
    return failure_of(r, "xrAttachSessionActionSets");
  active_sets_.clear();
  for (const XrActionSet set : sets) active_sets_.push_back({set, XR_NULL_PATH});
  return Done{};
}

void Session::sync_actions() {
  auto sync = tagged<XrActionsSyncInfo>(XR_TYPE_ACTIONS_SYNC_INFO);
  sync.countActiveActionSets = static_cast<std::uint32_t>(active_sets_.size());
  sync.activeActionSets = active_sets_.data();
  if (const XrResult r = xrSyncActions(session_.get(), &sync); fatal(r)) fail(r, "xrSyncActions");
  else if (XR_FAILED(r)) std::cerr << "curvlab: xr: " << failure_of(r, "xrSyncActions").message << '\n';
  synced_ = true;
}

// CLOCK_MONOTONIC → session clock. Reading the two clocks one after the
// other adds any preemption between the reads to the result, so the offset
// comes from the tightest of a few bracketed reads (monotonic, session,
// monotonic), kept for 5 s.
std::int64_t Session::monotonic_to_session() {
  const std::int64_t mono = monotonic_now_ns();
  if (offset_at_ns_ >= 0 && mono - offset_at_ns_ < 5'000'000'000) return offset_ns_;
  std::int64_t narrowest = std::numeric_limits<std::int64_t>::max();
  for (int i = 0; i < 5; ++i) {
    const std::int64_t before = monotonic_now_ns();
    const std::int64_t session = clock_->now_ns();
    const std::int64_t after = monotonic_now_ns();
    if (after - before < narrowest) {
      narrowest = after - before;
      offset_ns_ = session - (before + (after - before) / 2);
    }
  }
  offset_at_ns_ = mono;
  return offset_ns_;
}

std::int64_t Session::to_session_ns(XrTime t) {
  if (to_timespec_ != nullptr) {
    const auto convert = reinterpret_cast<PFN_xrConvertTimeToTimespecTimeKHR>(to_timespec_);
    timespec ts{};
    if (XR_SUCCEEDED(convert(instance_.handle(), t, &ts)))
      return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec + monotonic_to_session();
  }
#ifdef _WIN32
  if (to_counter_ != nullptr) {
    const auto convert = reinterpret_cast<PFN_xrConvertTimeToWin32PerformanceCounterKHR>(to_counter_);
    LARGE_INTEGER counter;
    if (XR_SUCCEEDED(convert(instance_.handle(), t, &counter)))
      return counter_ns(counter.QuadPart) + monotonic_to_session();
  }
#endif
  return clock_map_.to_session(t);
}

}  // namespace curvlab::harness::xr
