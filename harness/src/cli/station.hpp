// Where `curvlab run`, `resume` and `calibrate` open their devices (DESIGN.md
// §6; io/station.hpp): the display, pose source and response sources a lab
// sets up, from the command's options, before anything is written. The one
// place where they are composed, so a calibration runs on exactly the
// devices its session would.
#pragma once

#include "common.hpp"

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/devices/mapping.hpp"
#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/runner/headless.hpp"

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::xr {
class Session;
class Controllers;
class TrackedPoses;
class SwapchainDisplay;
}  // namespace curvlab::harness::xr

namespace curvlab::harness::cli {

struct BackendArgs {
  std::string backend = "headless";
  std::string pace = "fast";
  std::string render = "all";
  std::string images;
  std::string trajectory;
  std::optional<std::string> msaa;  // auto or a count: overrides the protocol's [viewing] msaa
  bool software = false;
  std::string window_size = "960x960";
  std::string preview = "side-by-side";
  std::string screenshot;
  std::string key_script;
  std::vector<std::string> responses;  // "KIND:ARGUMENT", e.g. "hid:MAPPING.toml"
  bool quiet = false;
  bool json = false;
  std::string export_dir;
  std::string progress = "bar";
  double progress_interval_s = 10.0;
  std::string operator_window = "auto";
  std::string operator_script;
  std::string operator_screenshot;
  std::string operator_eyes = "both";
};

// The session's devices (io/station.hpp), made before anything is written:
// a display that cannot start (no window system, no OpenXR runtime) leaves
// no trace. The one place where a display, a pose source and response
// sources are put together: the desktop window is all three at once; the
// headset is composed of its parts (its session, swapchain display, tracked
// poses and controllers, xr/*.hpp); headless is an offscreen display with
// poses from a trajectory, answered by the simulated observer
// (RunOptions::observer).
struct Devices {
  Devices();
  Devices(Devices&&) noexcept;
  Devices& operator=(Devices&&) noexcept;
  ~Devices();

  std::unique_ptr<harness::io::InteractiveDisplay> interactive;  // desktop
  harness::runner::HeadlessDevices headless;
  std::unique_ptr<harness::io::SteadyClock> steady;
  const harness::io::Clock* clock = nullptr;
  // The headset's parts (--backend xr). Each borrows the ones before it and
  // all read the clock, so they are destroyed in reverse order before it.
  std::unique_ptr<xr::Session> xr_session;
  std::unique_ptr<xr::Controllers> xr_controllers;
  std::unique_ptr<xr::TrackedPoses> xr_poses;
  std::unique_ptr<xr::SwapchainDisplay> xr_display;
  std::vector<std::unique_ptr<harness::io::ResponseSource>> response_devices;  // --responses
  // A headless run's --key-script: wraps the offscreen display it borrows.
  std::unique_ptr<desktop::ScriptedKeys> scripted_keys;
  harness::io::Station station;

  void use(harness::io::InteractiveDisplay& d) {
    station.display = &d;
    station.poses = &d;
    station.responses.push_back(&d);
  }
};

// What opening needs besides the options: the samples per pixel (already
// chosen; nullopt: auto, the display picks for its device), and for the headless display its refresh rate, eye images, the
// table its simulated participant stands at and where its clock starts.
struct StationNeeds {
  std::optional<std::uint32_t> msaa;
  int refresh_hz = 90;
  std::uint32_t width_px = 1024;
  std::uint32_t height_px = 1024;
  geometry::PhysicalTableFit table;
  std::int64_t start_ns = 0;
  // The protocol's timeline and answer keys a desktop key script is checked
  // against (nullopt: a calibration, which has no trials).
  std::optional<desktop::KeyScriptLimits> key_script_limits;
  bool stand_across = false;  // the desktop body starts across the table (a shared game's joiner)
};

// Opens --backend's display (with --responses' HID devices). A bad option
// or file is a UsageError (exit 2); a display or device that cannot start, a
// RuntimeFailure (exit 1). Warns when the device draws with fewer samples
// than asked.
Devices open_station(const BackendArgs& a, const StationNeeds& needs);

// The options with the protocol's [responses] HID mapping files added as
// --responses (resolved against the protocol file's folder), for desktop and
// xr runs, where a person answers; headless runs are answered by the
// simulated observer and keep the options as they are.
BackendArgs with_protocol_responses(BackendArgs a, const harness::protocol::Protocol& p);

// Every answer of the protocol must be one the devices of `a` (--backend's
// keyboard or controllers, --responses' HID devices) can give: a keys-only
// protocol in the headset would time out every trial. Returns what cannot be
// given ("PROTOCOL: the session's judgement (choice): the answer 'convex'
// (keys 1) cannot be given with --backend xr; …"), nullopt when all can or
// when no device answers (headless: the simulated observer, or nobody).
std::optional<std::string> unreachable_answer(const BackendArgs& a, const harness::protocol::Protocol& p);
// The same as a UsageError (exit 2), for run and resume before any device
// starts; nothing to check when the simulated observer answers.
void check_answers_reachable(const BackendArgs& a, const harness::protocol::Protocol& p, bool observer);

// Whether the run opens the operator window; a bad value is a usage error.
bool wants_operator_window(const BackendArgs& a);

// From now on SIGINT (Ctrl-C), SIGTERM and SIGHUP (a closed terminal) set the
// returned flag to the signal's number instead of ending the process, so a
// frame loop (a session, a calibration) can end in order, reading the flag
// once a frame; a second signal takes the default action (SA_RESETHAND),
// which SQLite survives too.
const std::atomic<int>& catch_stop_signals();
// The signal caught since, or 0.
int stop_signal_received();

}  // namespace curvlab::harness::cli
