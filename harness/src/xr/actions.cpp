#include "curvlab/harness/xr/actions.hpp"

namespace curvlab::harness::xr {

namespace {
constexpr const char* kSimple = "/interaction_profiles/khr/simple_controller";
constexpr const char* kTouch = "/interaction_profiles/oculus/touch_controller";
constexpr const char* kIndex = "/interaction_profiles/valve/index_controller";
constexpr const char* kVive = "/interaction_profiles/htc/vive_controller";

std::string left(const char* input) { return std::string(kLeftHand) + "/input/" + input; }
std::string right(const char* input) { return std::string(kRightHand) + "/input/" + input; }

// A profile's bindings: both hands' grip and aim poses, then `controls`.
ProfileBindings with_poses(const char* profile, std::vector<SuggestedBinding> controls) {
  ProfileBindings p{profile,
                    {{"grip_pose", left("grip/pose")},
                     {"grip_pose", right("grip/pose")},
                     {"aim_pose", left("aim/pose")},
                     {"aim_pose", right("aim/pose")}}};
  p.bindings.insert(p.bindings.end(), controls.begin(), controls.end());
  return p;
}

// Both triggers' values, the right hand's inputs for A and B and the left
// hand's for X and Y.
std::vector<SuggestedBinding> trigger_and_buttons(const char* a, const char* b, const char* x,
                                                  const char* y) {
  return {{"trigger", left("trigger/value")},
          {"trigger", right("trigger/value")},
          {"button_a", right(a)},
          {"button_b", right(b)},
          {"button_x", left(x)},
          {"button_y", left(y)}};
}
}  // namespace

ActionSetDef curvlab_action_set() {
  const std::vector<std::string> both = {kLeftHand, kRightHand};
  ActionSetDef set;
  set.name = "curvlab";
  set.localized_name = "curvlab experiment";
  set.actions = {
      {"grip_pose", "Hand (grip) pose", ActionType::Pose, both},
      {"aim_pose", "Pointing (aim) pose", ActionType::Pose, both},
      {"trigger", "Trigger", ActionType::Float, both},
      {"button_a", "A button", ActionType::Boolean, {kRightHand}},
      {"button_b", "B button", ActionType::Boolean, {kRightHand}},
      {"button_x", "X button", ActionType::Boolean, {kLeftHand}},
      {"button_y", "Y button", ActionType::Boolean, {kLeftHand}},
  };
  // The simple controller has no face buttons: select is the trigger, and
  // menu stands in for the primary button of each hand (A right, X left).
  set.profiles.push_back(with_poses(kSimple, {{"trigger", left("select/click")},
                                              {"trigger", right("select/click")},
                                              {"button_a", right("menu/click")},
                                              {"button_x", left("menu/click")}}));
  set.profiles.push_back(with_poses(kTouch, trigger_and_buttons("a/click", "b/click", "x/click", "y/click")));
  // Index controllers have A and B on both hands: the left hand's stand for
  // X and Y, as on Touch controllers (and as runtimes emulate Touch on Index).
  set.profiles.push_back(with_poses(kIndex, trigger_and_buttons("a/click", "b/click", "a/click", "b/click")));
  // Vive wands: the trackpad's click is the primary button (A right, X left)
  // and the menu button the secondary one (B, Y).
  set.profiles.push_back(
      with_poses(kVive, trigger_and_buttons("trackpad/click", "menu/click", "trackpad/click", "menu/click")));
  return set;
}

std::string protocol_button(const std::string& action, bool left_hand) {
  if (action == "trigger") return left_hand ? "left_trigger" : "right_trigger";
  if (action.rfind("button_", 0) == 0) return action.substr(7);
  return action;
}

harness::io::Intents controller_intents(const std::string& button) {
  using harness::io::Intent;
  if (button == "right_trigger") return {Intent::continue_page, Intent::calibration_touch};
  if (button == "left_trigger") return {Intent::continue_page};
  if (button == "a") return {Intent::continue_page, Intent::calibration_accept};
  if (button == "b") return {Intent::calibration_fit_three, Intent::calibration_redo};
  return {};
}

harness::io::InputEvent controller_input(std::int64_t t_ns, bool left_hand, std::string button, bool pressed) {
  harness::io::InputEvent in;
  in.t_ns = t_ns;
  in.source = {harness::io::SourceKind::xr_controller, left_hand ? "left" : "right"};
  in.intents = controller_intents(button);
  in.control = {harness::io::ControlKind::button, std::move(button)};
  in.pressed = pressed;
  return in;
}

std::vector<std::string> profile_input_paths(const std::string& profile) {
  std::vector<std::string> out;
  auto both = [&out](const char* input) {
    out.push_back(left(input));
    out.push_back(right(input));
  };
  if (profile == kSimple) {
    for (const char* in : {"select/click", "menu/click", "grip/pose", "aim/pose"}) both(in);
  } else if (profile == kTouch) {
    for (const char* in : {"x/click", "x/touch", "y/click", "y/touch", "menu/click"}) out.push_back(left(in));
    for (const char* in : {"a/click", "a/touch", "b/click", "b/touch", "system/click"})
      out.push_back(right(in));
    for (const char* in :
         {"squeeze/value", "trigger/value", "trigger/touch", "thumbstick/x", "thumbstick/y",
          "thumbstick/click", "thumbstick/touch", "thumbrest/touch", "grip/pose", "aim/pose"})
      both(in);
  } else if (profile == kIndex) {
    // OpenXR 1.0 §6.4, "Valve Index Controller Profile".
    for (const char* in :
         {"system/click",  "system/touch",  "a/click",        "a/touch",          "b/click",
          "b/touch",       "squeeze/value", "squeeze/force",  "trigger/click",    "trigger/value",
          "trigger/touch", "thumbstick/x",  "thumbstick/y",   "thumbstick/click", "thumbstick/touch",
          "trackpad/x",    "trackpad/y",    "trackpad/force", "trackpad/touch",   "grip/pose",
          "aim/pose"})
      both(in);
  } else if (profile == kVive) {
    // OpenXR 1.0 §6.4, "HTC Vive Controller Profile".
    for (const char* in :
         {"system/click", "squeeze/click", "menu/click", "trigger/click", "trigger/value", "trackpad/x",
          "trackpad/y", "trackpad/click", "trackpad/touch", "grip/pose", "aim/pose"})
      both(in);
  }
  return out;
}

}  // namespace curvlab::harness::xr
