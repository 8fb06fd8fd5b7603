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

// What a key script is checked against before the window opens (the
// protocol's timeline, key_script.hpp): each timed phase's shortest length
// across the protocol's blocks and the keys that answer.
struct KeyScriptLimits {
  std::string protocol;  // its file, for messages
  std::int64_t fixation_ms = 0;
  std::int64_t stimulus_ms = 0;
  std::int64_t response_ms = 0;
  std::int64_t iti_ms = 0;
  std::vector<std::string> answer_keys;  // lower case, as the script names keys
};

struct DesktopOptions {
  std::uint32_t eye_width_px = 960;  // per eye
  std::uint32_t eye_height_px = 960;
  DesktopPreview preview = DesktopPreview::side_by_side;
  // Screenshots go here: every trial's first stimulus frame, and F12.
  // Empty: screenshots only on F12, into the current directory.
  std::string screenshot_dir;
  // A file of key presses made for the participant (scripted pilots and
  // tests): one `KEY [PHASE+DELAY_MS | DELAY_MS]` per line, '#' comments
  // (key_script.hpp; docs/lab.md, "Key scripts"). Empty: none.
  std::string key_script;
  // Checked against these before the window opens, when given.
  std::optional<KeyScriptLimits> key_script_limits;
  bool software = false;  // lavapipe even with a GPU
  bool vsync = true;
  std::optional<std::uint32_t> msaa;  // samples per pixel requested (clamped); nullopt: the device's automatic count
  bool validation = false;  // Khronos validation layer on (tests); messages go to stderr
  // The body starts across the table, outside its −z edge (a shared game's
  // joiner, so that the two players face each other from the first frame).
  bool stand_across = false;
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

// A key script typed into a display that has no keyboard (a headless run,
// `run --key-script` without --backend desktop): the display's frames pass
// through unchanged, and the script's keys arrive as inputs of the `script`
// device on the display's clock, simulated or real, by the rules of the
// desktop window's script (docs/lab.md, "Key scripts"). A scripted Escape
// ends the session, resumable; a script used up at a page ends it with a
// message. Borrows the display and clock, which must outlive it.
class ScriptedKeys : public harness::io::Display, public harness::io::ResponseSource {};
// A bad line (a hand line among them: there is no body to move) is an Error
// naming FILE:LINE.
harness::Result<std::unique_ptr<ScriptedKeys>> make_scripted_keys(harness::io::Display& inner,
                                                                  const harness::io::Clock& clock,
                                                                  const std::string& script,
                                                                  const std::optional<KeyScriptLimits>& limits);

}  // namespace curvlab::harness::desktop
