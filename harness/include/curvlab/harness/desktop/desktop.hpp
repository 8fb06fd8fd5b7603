// The desktop window for piloting a protocol (DESIGN.md §6): a GLFW window
// with a Vulkan swapchain, both eyes side by side or one eye, the keyboard
// and mouse moving the head and hands, trial information on screen, and
// screenshots. Needs a display (X11 or Wayland; Xvfb works).
#pragma once

#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::desktop {

enum class DesktopPreview { side_by_side, left, right };

struct DesktopOptions {
  std::uint32_t eye_width_px = 960;  // per eye
  std::uint32_t eye_height_px = 960;
  DesktopPreview preview = DesktopPreview::side_by_side;
  // Screenshots go here: every trial's first stimulus frame, and F12.
  // Empty: screenshots only on F12, into the current directory.
  std::string screenshot_dir;
  // A file of key presses made for the participant (scripted pilots and
  // tests): one `KEY [DELAY_MS]` per line, '#' comments. Each key is pressed
  // DELAY_MS (default 300) after the runner next waits for input (overlay
  // phase instructions, response or break). Empty: none.
  std::string key_script;
  bool software = false;  // lavapipe even with a GPU
  bool vsync = true;
  std::optional<std::uint32_t> msaa;  // samples per pixel requested (clamped); nullopt: the device's automatic count
  bool validation = false;  // Khronos validation layer on (tests); messages go to stderr
  const harness::io::Clock* clock = nullptr;  // the session's; required
};

// What the window's keyboard can press: every key; pages continue on space.
harness::io::Reach keyboard_reach();

// What a key means to a session, whoever types it (the window's keyboard,
// its key script): space, enter and return continue a page; in the table
// calibration space touches, F fits three corners, Enter keeps the fit and
// R touches again. Other keys mean nothing by themselves (they answer
// through the protocol's `keys`).
harness::io::Intents key_intents(const std::string& key);
// A key's press or release as an input of the keyboard (or, with
// `source` script, of the key script).
harness::io::InputEvent key_input(std::int64_t t_ns, std::string key, bool pressed,
                                  harness::io::SourceKind source = harness::io::SourceKind::keyboard);

// The key legend the window's banner shows for what is on screen: on a page
// "space: continue"; during a trial the question, each answer with its keys
// ("1 convex · 2 straight · 3 concave"; an answer bound to no key says so)
// and the value a method varies; "" otherwise.
std::string legend_text(const harness::io::Overlay& overlay);

// The window as display, pose source (keyboard and mouse move the head and
// hands) and response source (keys). No display or no Vulkan: an Error of
// kind `device`.
harness::Result<std::unique_ptr<harness::io::InteractiveDisplay>> make_desktop_backend(const DesktopOptions& options);

}  // namespace curvlab::harness::desktop
