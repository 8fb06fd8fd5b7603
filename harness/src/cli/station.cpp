#include "station.hpp"

#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/tracking/trajectory_csv.hpp"
#include "curvlab/harness/xr/controllers.hpp"
#include "curvlab/harness/xr/session.hpp"
#include "curvlab/harness/xr/swapchain_display.hpp"
#include "curvlab/harness/xr/tracked_poses.hpp"

#include "curvlab/harness/platform/signals.hpp"

#include <filesystem>
#include <cstdlib>
#include <tuple>

namespace curvlab::harness::cli {
namespace {

namespace rn = curvlab::harness::runner;

bool display_present() {
  const char* x = std::getenv("DISPLAY");
  const char* wl = std::getenv("WAYLAND_DISPLAY");
  return (x != nullptr && *x != '\0') || (wl != nullptr && *wl != '\0');
}

rn::HeadlessOptions headless_options(const BackendArgs& a, const StationNeeds& n) {
  rn::HeadlessOptions o;
  if (a.pace == "fast") o.pace = rn::Pace::fast;
  else if (a.pace == "realtime") o.pace = rn::Pace::realtime;
  else throw UsageError("--pace must be fast or realtime, got '" + a.pace + "'");
  o.refresh_hz = n.refresh_hz;
  o.width_px = n.width_px;
  o.height_px = n.height_px;
  o.software = a.software;
  o.msaa = n.msaa;
  o.start_ns = n.start_ns;
  // A session that draws nothing needs no Vulkan device: a dry run with the
  // simulated participant works on any machine (the image observer draws
  // with a device of its own).
  o.no_gpu = rn::parse_frame_drawing(a.render) == rn::FrameDrawing::none && a.images.empty();
  return o;
}

void open_headless(Devices& out, const BackendArgs& a, const StationNeeds& n) {
  rn::TrajectoryOptions t;
  t.table = n.table;
  if (!a.trajectory.empty()) {
    auto file = harness::read_trajectory_csv(a.trajectory);
    if (!file) raise(file.error());
    t.trajectory = file.value().samples;
    if (t.trajectory.empty()) throw UsageError(a.trajectory + ": the trajectory has no samples");
  }
  auto made = rn::HeadlessDevices::create(headless_options(a, n), std::move(t));
  if (!made) raise(made.error());
  out.headless = std::move(made).value();
  out.clock = &out.headless.clock();
  out.station = out.headless.station();
  if (!a.key_script.empty()) {
    auto keys = desktop::make_scripted_keys(*out.station.display, *out.clock, a.key_script, n.key_script_limits);
    if (!keys) raise(keys.error());
    out.scripted_keys = std::move(keys).value();
    out.station.display = out.scripted_keys.get();
    out.station.responses.push_back(out.scripted_keys.get());
  }
}

// The headset, composed of its parts as hello_xr composes its plugins, in
// the order of the OpenXR lifecycle: the session (instance, system, the
// Vulkan device the runtime makes, xrCreateSession), the controllers' action
// set, the tracked poses (reference spaces; the action sets attached; the
// grip spaces and eye trackers), then the swapchain display (refresh rate,
// swapchains, renderer). The display, the poses and the controllers are the
// station's display, pose source and first response source.
void open_headset(Devices& out, const BackendArgs& a, const StationNeeds& n) {
  const bool mirror = wants_operator_window(a);
  auto session = xr::Session::create({.application_name = "curvlab", .clock = out.clock});
  if (!session) raise(session.error());
  out.xr_session = std::move(session).value();
  auto controllers = xr::Controllers::create(*out.xr_session);
  if (!controllers) raise(controllers.error());
  out.xr_controllers = std::move(controllers).value();
  auto poses = xr::TrackedPoses::create(*out.xr_session, *out.xr_controllers);
  if (!poses) raise(poses.error());
  out.xr_poses = std::move(poses).value();
  auto display = xr::SwapchainDisplay::create(
      *out.xr_session, *out.xr_poses,
      {.mirror = mirror, .msaa = n.msaa, .refresh_hz = n.refresh_hz});
  if (!display) raise(display.error());
  out.xr_display = std::move(display).value();
  out.station.display = out.xr_display.get();
  out.station.poses = out.xr_poses.get();
  out.station.responses.push_back(out.xr_controllers.get());
}

Devices open_devices_of_kind(const BackendArgs& a, const StationNeeds& n) {
  Devices out;
  if (a.backend == "headless") {
    open_headless(out, a, n);
    return out;
  }
  out.steady = std::make_unique<harness::io::SteadyClock>();
  out.clock = out.steady.get();
  if (a.backend == "desktop") {
    desktop::DesktopOptions o;
    std::tie(o.eye_width_px, o.eye_height_px) = parse_size(a.window_size, "--window-size");
    if (a.preview == "side-by-side") o.preview = desktop::DesktopPreview::side_by_side;
    else if (a.preview == "left") o.preview = desktop::DesktopPreview::left;
    else if (a.preview == "right") o.preview = desktop::DesktopPreview::right;
    else throw UsageError("--preview must be side-by-side, left or right, got '" + a.preview + "'");
    o.screenshot_dir = a.screenshot;
    o.key_script = a.key_script;
    o.key_script_limits = n.key_script_limits;
    o.software = a.software;
    o.msaa = n.msaa;
    o.stand_across = n.stand_across;
    o.clock = out.clock;
    auto made = desktop::make_desktop_backend(o);
    if (!made) raise(made.error());
    out.interactive = std::move(made).value();
    out.use(*out.interactive);
  } else if (a.backend == "xr") {
    open_headset(out, a, n);
  } else {
    throw UsageError("--backend must be headless, desktop or xr, got '" + a.backend + "'");
  }
  return out;
}

// The kinds of device --responses KIND:ARGUMENT opens, one entry each: a
// new kind of response device is its source (an io::ResponseSource under
// harness/src/devices/) and one entry here.
struct ResponseKind {
  std::string_view name;      // before the colon
  std::string_view argument;  // what follows it, for the usage message
  // What the device can press, from the argument alone (a bad one: exit 2).
  harness::io::Reach (*reach)(const std::string& argument);
  // The device, opened (an absent one: exit 1).
  std::unique_ptr<harness::io::ResponseSource> (*open)(const std::string& argument, const harness::io::Clock& clock);
};

devices::MappingFile hid_mapping(const std::string& path) {
  auto file = devices::load_mapping(path);
  if (!file) raise(file.error());
  return std::move(file).value();
}

const ResponseKind kResponseKinds[] = {
    {"hid", "MAPPING.toml (a HID mapping file, docs/devices.md)",
     [](const std::string& path) { return devices::mapping_reach(hid_mapping(path)); },
     [](const std::string& path, const harness::io::Clock& clock) -> std::unique_ptr<harness::io::ResponseSource> {
       auto opened = devices::HidResponses::open(hid_mapping(path), clock);
       if (!opened) raise(opened.error());
       return std::move(opened).value();
     }},
};

// Each --responses value's kind and argument; an unknown kind: exit 2.
std::vector<std::pair<const ResponseKind*, std::string>> response_specs(const BackendArgs& a) {
  std::vector<std::pair<const ResponseKind*, std::string>> out;
  for (const auto& spec : a.responses) {
    const auto colon = spec.find(':');
    const ResponseKind* kind = nullptr;
    for (const auto& k : kResponseKinds)
      if (colon != std::string::npos && spec.compare(0, colon, k.name) == 0) kind = &k;
    if (kind == nullptr) {
      std::string expected;
      for (const auto& k : kResponseKinds)
        expected += (expected.empty() ? "" : " or ") + std::string(k.name) + ":" + std::string(k.argument);
      throw UsageError("--responses " + spec + ": expected " + expected);
    }
    out.emplace_back(kind, spec.substr(colon + 1));
  }
  return out;
}

// The response devices of --responses, each one connected, before anything
// is written: a bad argument is bad input (exit 2), an absent device a
// device error (exit 1).
void open_responses(Devices& out, const BackendArgs& a) {
  if (a.responses.empty()) return;
  if (a.backend == "headless" && a.pace == "fast")
    throw UsageError("--responses needs a person answering in real time: add --pace realtime, or use --backend "
                     "desktop or xr");
  for (const auto& [kind, argument] : response_specs(a)) {
    out.response_devices.push_back(kind->open(argument, *out.clock));
    out.station.responses.push_back(out.response_devices.back().get());
  }
}

}  // namespace

Devices::Devices() = default;
Devices::Devices(Devices&&) noexcept = default;
Devices& Devices::operator=(Devices&&) noexcept = default;
Devices::~Devices() = default;

// Whether the run opens the operator window; a bad value is a usage error.
bool wants_operator_window(const BackendArgs& a) {
  if (a.operator_window == "off") return false;
  if (a.operator_window == "on") return true;
  if (a.operator_window != "auto")
    throw UsageError("--operator-window must be auto, on or off, got '" + a.operator_window + "'");
  // The desktop pilot's own window is the participant's view: its panel opens on request.
  return a.backend == "xr" && display_present();
}

// The signal that asked a frame loop to stop (0: none): platform/signals.hpp.
const std::atomic<int>& catch_stop_signals() { return platform::catch_stop_signals(); }

int stop_signal_received() { return platform::stop_signal_received(); }

BackendArgs with_protocol_responses(BackendArgs a, const harness::protocol::Protocol& p) {
  if (a.backend != "desktop" && a.backend != "xr") return a;
  const std::filesystem::path folder = std::filesystem::path(p.file).parent_path();
  for (const auto& m : p.hid_mappings) {
    const std::filesystem::path path(m);
    a.responses.push_back("hid:" + (path.is_absolute() ? path : folder / path).string());
  }
  return a;
}

std::optional<std::string> unreachable_answer(const BackendArgs& a, const harness::protocol::Protocol& p) {
  std::vector<harness::io::Reach> reach;
  if (a.backend == "desktop") reach.push_back(desktop::keyboard_reach());
  if (a.backend == "xr") reach.push_back(xr::controller_reach());
  for (const auto& [kind, argument] : response_specs(a)) reach.push_back(kind->reach(argument));
  if (reach.empty()) return std::nullopt;
  const auto missing = harness::runner::unreachable_answer(reach, p);
  if (!missing) return std::nullopt;
  std::string with = "--backend " + a.backend;
  for (const auto& r : a.responses) with += " --responses " + r;
  return p.file + ": " + *missing + " cannot be given with " + with +
         "; bind it to an input these devices have (docs/protocols.md, \"Key and button names\")";
}

void check_answers_reachable(const BackendArgs& a, const harness::protocol::Protocol& p, bool observer) {
  if (observer) return;
  if (auto missing = unreachable_answer(a, p)) throw UsageError(*missing);
}

Devices open_station(const BackendArgs& a, const StationNeeds& needs) {
  Devices out = open_devices_of_kind(a, needs);
  if (needs.msaa) warn_if_msaa_clamped(*needs.msaa, out.station.display->info().msaa);
  open_responses(out, a);
  return out;
}

}  // namespace curvlab::harness::cli
