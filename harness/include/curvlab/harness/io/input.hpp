// What an input is, typed from the device edge inward (DESIGN.md §6): the
// source it came from, the control pressed (for the record), and what it
// asks of the session. Each response source maps its own keys and buttons to
// intents — the desktop window's keyboard and key script
// (desktop/desktop.hpp, key_input), HID devices through their mapping file
// (devices/responses.hpp, response_input), the headset's controllers
// (xr/actions.hpp, controller_input), the simulated observer
// (harness/src/runner/observer_keys.hpp) — so the runner branches on intents
// and never on a key, button or device name. An answer is the one exception:
// which control answers is the protocol's to say (an option's `keys` and
// `buttons`), so it is found by answer_index() through the bindings of the
// judgement on screen.
//
// Strings appear only at the edge: to_string(SourceId) is what the database
// stores as a trial's response_device and in early_input events
// (data_schema/codebook.md).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::io {

// The kinds of response source.
enum class SourceKind : std::uint8_t {
  keyboard,       // the desktop window's keys
  script,         // the desktop window's key script (scripted pilots and tests)
  hid,            // a HID device of a mapping file (button box, pedal, gamepad)
  xr_controller,  // a headset's controller
  observer,       // the simulated observer
};

// One source: its kind and, where a kind has several, which one — the HID
// device's name in its mapping file, the controller's hand ("left",
// "right"); empty for the others.
struct SourceId {
  SourceKind kind = SourceKind::keyboard;
  std::string name;
  friend bool operator==(const SourceId&, const SourceId&) = default;
};

// As stored: "keyboard", "script", "hid:<name>", "xr:<hand>", "observer".
inline std::string to_string(const SourceId& id) {
  switch (id.kind) {
    case SourceKind::keyboard: return "keyboard";
    case SourceKind::script: return "script";
    case SourceKind::hid: return "hid:" + id.name;
    case SourceKind::xr_controller: return "xr:" + id.name;
    case SourceKind::observer: return "observer";
  }
  return "unknown";
}

// A key is answered through an answer's `keys`, a button (a HID mapping's
// response, a controller's button) through its `buttons`.
enum class ControlKind : std::uint8_t { key, button };

// The control pressed, as the source names it: a key's GLFW-style lower-case
// name ("1", "left", "space"), a button's name from the mapping file or the
// controllers' action set ("a", "right_trigger"). Kept for the record (early
// inputs, logs) and for the protocol's answer bindings.
struct Control {
  ControlKind kind = ControlKind::key;
  std::string name;
  friend bool operator==(const Control&, const Control&) = default;
};

// What an input asks of the session whatever the judgement on screen. One
// control may mean several (a controller's A continues a page and keeps a
// table calibration); the step on screen takes the one it understands.
enum class Intent : std::uint8_t {
  continue_page,          // turn an instruction, break or closing page
  calibration_touch,      // take the touching tip as the next table corner
  calibration_fit_three,  // fit the three corners touched so far
  calibration_accept,     // keep the fitted table
  calibration_redo,       // touch the corners again
  cue_strike,             // strike with the cue (play blocks): the desktop's space key, held and let go
};

inline std::string_view to_string(Intent intent) {
  switch (intent) {
    case Intent::continue_page: return "continue";
    case Intent::calibration_touch: return "calibration_touch";
    case Intent::calibration_fit_three: return "calibration_fit_three";
    case Intent::calibration_accept: return "calibration_accept";
    case Intent::calibration_redo: return "calibration_redo";
    case Intent::cue_strike: return "cue_strike";
  }
  return "unknown";
}

// A set of intents; a plain value.
class Intents {
 public:
  constexpr Intents() = default;
  constexpr Intents(std::initializer_list<Intent> intents) {
    for (const Intent i : intents) bits_ |= bit(i);
  }
  [[nodiscard]] constexpr bool has(Intent i) const { return (bits_ & bit(i)) != 0; }
  [[nodiscard]] constexpr bool empty() const { return bits_ == 0; }
  constexpr Intents& operator|=(Intents other) {
    bits_ |= other.bits_;
    return *this;
  }
  friend constexpr bool operator==(Intents, Intents) = default;

 private:
  static constexpr std::uint32_t bit(Intent i) { return std::uint32_t{1} << static_cast<unsigned>(i); }
  std::uint32_t bits_ = 0;
};

// One discrete input: a press or release of one control of one source.
struct InputEvent {
  std::int64_t t_ns = 0;  // session clock
  SourceId source;
  Control control;
  Intents intents;  // what the source makes of the control
  bool pressed = true;
};

// The answer among `answers` (each with `keys` and `buttons`, the judgement
// on screen's, in its order) that `control` gives: a key through the
// answers' keys, a button through their buttons; the first that binds it,
// or nullopt. A template over the answer type so the protocol's bindings and
// io's own (AnswerInputs, frame.hpp) are read alike.
template <class Answer>
std::optional<std::size_t> answer_index(const std::vector<Answer>& answers, const Control& control) {
  for (std::size_t k = 0; k < answers.size(); ++k) {
    const auto& names = control.kind == ControlKind::key ? answers[k].keys : answers[k].buttons;
    if (std::find(names.begin(), names.end(), control.name) != names.end()) return k;
  }
  return std::nullopt;
}

}  // namespace curvlab::harness::io
