// The controller actions curvlab uses, as data: one action set with both
// hands' grip and aim poses, the trigger, and the A/B/X/Y buttons, with
// suggested bindings for the Khronos simple controller and the Oculus Touch
// controller (the profile most runtimes can remap to others). Pure data, so
// the binding table is tested without a runtime; xr/instance.hpp creates
// them.
#pragma once

#include "curvlab/harness/io/input.hpp"

#include <cstdint>
#include <string>
#include <vector>

namespace curvlab::harness::xr {

inline constexpr const char* kLeftHand = "/user/hand/left";
inline constexpr const char* kRightHand = "/user/hand/right";

enum class ActionType { Pose, Boolean, Float };

struct ActionDef {
  std::string name;            // OpenXR path component: lower-case, digits, '-', '_', '.'
  std::string localized_name;  // shown in the runtime's rebinding UI
  ActionType type = ActionType::Boolean;
  std::vector<std::string> subaction_paths;  // hands the action is read per
};

struct SuggestedBinding {
  std::string action;  // ActionDef::name
  std::string path;    // e.g. /user/hand/left/input/grip/pose
};

struct ProfileBindings {
  std::string profile;  // e.g. /interaction_profiles/oculus/touch_controller
  std::vector<SuggestedBinding> bindings;
};

struct ActionSetDef {
  std::string name;
  std::string localized_name;
  unsigned priority = 0;
  std::vector<ActionDef> actions;
  std::vector<ProfileBindings> profiles;
};

// The action set of a curvlab session.
ActionSetDef curvlab_action_set();

// The name an action's input events carry: the protocol's button names
// (docs/protocols.md, "Key and button names") that judgement options bind —
// button_a → "a", …, the trigger → "left_trigger" / "right_trigger".
// Other actions keep their own name.
std::string protocol_button(const std::string& action, bool left_hand);

// What a controller's button (a protocol_button name) means to a session:
// either trigger or A continues a page; in the table calibration the right
// trigger touches, B fits three corners or touches again, A keeps the fit.
harness::io::Intents controller_intents(const std::string& button);
// A button's press or release as an input of the controller in that hand
// (device "xr:left" / "xr:right"): one event, with every intent it has.
harness::io::InputEvent controller_input(std::int64_t t_ns, bool left_hand, std::string button, bool pressed);

// Input paths each profile offers (from the OpenXR specification's
// interaction-profile tables), to check the bindings against.
std::vector<std::string> profile_input_paths(const std::string& profile);

}  // namespace curvlab::harness::xr
