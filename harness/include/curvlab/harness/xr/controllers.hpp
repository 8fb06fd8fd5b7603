// The headset's controllers as a response source (io/response_source.hpp):
// curvlab's action set (actions.hpp) with its suggested bindings, attached to
// the session with the eye gaze's (tracked_poses.hpp), and the presses read
// from it each frame while the session is FOCUSED. Events carry the
// protocol's button names (a, b, x, y, left_trigger, right_trigger) and
// their intents (actions.hpp, controller_intents): a trigger or A continues
// a page with the same one event that may answer.
//
// Action states are those of the last xrSyncActions (OpenXR 1.0 §11.5). An
// action that was inactive (no focus) gives its first state as a baseline,
// not an event: a button or trigger held across the focus return is no new
// press, and nothing that changed before the return is delivered.
#pragma once

#include "curvlab/harness/io/response_source.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/xr/instance.hpp"
#include "curvlab/harness/xr/session.hpp"

#include <openxr/openxr.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::xr {

// What the controllers of curvlab's action set can press (button names as
// protocols write them); pages continue on a trigger or A.
harness::io::Reach controller_reach();

// A trigger's analogue value as a button: a press above 0.75, a release below
// 0.25, so a finger resting half-way does not chatter. A pure value.
class TriggerHysteresis {
 public:
  static constexpr float kPress = 0.75f;
  static constexpr float kRelease = 0.25f;
  // The trigger reads `value`. A baseline read (the first since the action
  // became active) takes the state without an event. Returns the new state
  // where it changed (an event), else nullopt.
  std::optional<bool> update(float value, bool baseline);
  [[nodiscard]] bool down() const { return down_; }

 private:
  bool down_ = false;
};

// Owns curvlab's action set (destroyed before the session it was attached
// to). Borrows the session; used on the frame thread only, not thread-safe.
class Controllers final : public harness::io::ResponseSource, private SessionPart {
 public:
  // Creates the action set and suggests its bindings (before the attach,
  // which the tracked poses make with the eye gaze's set).
  static harness::Result<std::unique_ptr<Controllers>> create(Session& session);
  ~Controllers() override;

  // The buttons pressed and released since the last call, while FOCUSED.
  harness::io::Signal poll(std::vector<harness::io::InputEvent>& out) override;
  [[nodiscard]] harness::io::Reach reach() const override { return controller_reach(); }

  [[nodiscard]] XrActionSet action_set() const { return actions_.handle(); }
  [[nodiscard]] XrAction action(std::string_view name) const { return actions_.action(name); }
  // /user/hand/left (0) and /user/hand/right (1).
  [[nodiscard]] XrPath hand(std::size_t i) const { return hands_[i]; }

 private:
  Controllers(Session& session, ActionSet actions) : session_(session), actions_(std::move(actions)) {}
  void on_focus_lost() override;
  void read_buttons(std::vector<harness::io::InputEvent>& out);
  void read_boolean(std::size_t action, std::size_t hand, const XrActionStateGetInfo& get,
                    std::vector<harness::io::InputEvent>& out);
  void read_trigger(std::size_t action, std::size_t hand, const XrActionStateGetInfo& get,
                    std::vector<harness::io::InputEvent>& out);
  // Says a failed action-state query once per call name (it repeats every
  // frame otherwise) and goes on: one unreadable button must not end a session.
  void report_once(XrResult r, const char* call);

  Session& session_;
  ActionSet actions_;
  ActionSetDef def_ = curvlab_action_set();
  std::array<XrPath, 2> hands_{XR_NULL_PATH, XR_NULL_PATH};
  std::array<TriggerHysteresis, 2> triggers_;
  // Per action of curvlab_action_set() and hand: active at the last read
  // (false after a focus loss, so the first read after it is a baseline).
  std::vector<std::array<bool, 2>> active_ = std::vector<std::array<bool, 2>>(def_.actions.size());
  std::vector<std::string> reported_;
};

}  // namespace curvlab::harness::xr
