#include "curvlab/harness/xr/controllers.hpp"

#include <algorithm>
#include <iostream>

namespace curvlab::harness::xr {

using harness::io::InputEvent;
using harness::io::Signal;

std::optional<bool> TriggerHysteresis::update(float value, bool baseline) {
  const bool was = down_;
  const bool now = was ? value > kRelease : value > kPress;
  if (baseline) {
    down_ = value > kPress;
    return std::nullopt;
  }
  if (now == was) return std::nullopt;
  down_ = now;
  return now;
}

harness::Result<std::unique_ptr<Controllers>> Controllers::create(Session& session) {
  auto set = ActionSet::create(session.instance(), curvlab_action_set());
  if (!set) return set.error();
  std::unique_ptr<Controllers> c(new Controllers(session, std::move(set).value()));
  for (std::size_t i = 0; i < 2; ++i)
    if (const XrResult r = xrStringToPath(session.instance().handle(), i == 0 ? kLeftHand : kRightHand, &c->hands_[i]);
        XR_FAILED(r))
      return failure_of(r, "xrStringToPath");
  session.join(*c);
  return c;
}

Controllers::~Controllers() { session_.leave(*this); }

void Controllers::on_focus_lost() {
  for (auto& hands : active_) hands = {false, false};
}

Signal Controllers::poll(std::vector<InputEvent>& out) {
  if (!session_.failed() && session_.mode() == RunMode::Running) read_buttons(out);
  return Signal::none;
}

void Controllers::report_once(XrResult r, const char* call) {
  if (fatal(r)) session_.fail(r, call);
  if (std::find(reported_.begin(), reported_.end(), call) != reported_.end()) return;
  reported_.emplace_back(call);
  std::cerr << "curvlab: xr: " << failure_of(r, call).message << '\n';
}

// The frame on which focus returns began unfocused, without a sync: its
// states would be the ones synced before the focus loss, so it syncs here.
void Controllers::read_buttons(std::vector<InputEvent>& out) {
  if (!session_.synced()) session_.sync_actions();
  for (std::size_t k = 0; k < def_.actions.size(); ++k) {
    const auto& a = def_.actions[k];
    if (a.type == ActionType::Pose) continue;
    for (const auto& sub : a.subaction_paths) {
      const std::size_t hand = sub == kLeftHand ? 0 : 1;
      auto get = tagged<XrActionStateGetInfo>(XR_TYPE_ACTION_STATE_GET_INFO);
      get.action = actions_.action(a.name);
      get.subactionPath = hands_[hand];
      if (a.type == ActionType::Boolean) read_boolean(k, hand, get, out);
      else read_trigger(k, hand, get, out);
    }
  }
}

// Events carry the protocol's button names (docs/protocols.md, "Key and
// button names"), which is what judgement options bind, and what the button
// means whatever is on screen (controller_intents): one event per change.
void Controllers::read_boolean(std::size_t k, std::size_t hand, const XrActionStateGetInfo& get,
                               std::vector<InputEvent>& out) {
  auto st = tagged<XrActionStateBoolean>(XR_TYPE_ACTION_STATE_BOOLEAN);
  if (const XrResult r = xrGetActionStateBoolean(session_.handle(), &get, &st); XR_FAILED(r)) {
    report_once(r, "xrGetActionStateBoolean");
    return;
  }
  bool& was_active = active_[k][hand];
  const bool baseline = !was_active;
  was_active = st.isActive == XR_TRUE;
  if (st.isActive != XR_TRUE || st.changedSinceLastSync != XR_TRUE || baseline ||
      st.lastChangeTime < session_.focused_at())
    return;
  out.push_back(controller_input(session_.to_session_ns(st.lastChangeTime), hand == 0,
                                 protocol_button(def_.actions[k].name, hand == 0), st.currentState == XR_TRUE));
}

void Controllers::read_trigger(std::size_t k, std::size_t hand, const XrActionStateGetInfo& get,
                               std::vector<InputEvent>& out) {
  auto st = tagged<XrActionStateFloat>(XR_TYPE_ACTION_STATE_FLOAT);
  if (const XrResult r = xrGetActionStateFloat(session_.handle(), &get, &st); XR_FAILED(r)) {
    report_once(r, "xrGetActionStateFloat");
    return;
  }
  bool& was_active = active_[k][hand];
  const bool baseline = !was_active;
  was_active = st.isActive == XR_TRUE;
  if (st.isActive != XR_TRUE) return;
  const auto pressed = triggers_[hand].update(st.currentState, baseline);
  if (!pressed) return;
  out.push_back(controller_input(session_.to_session_ns(st.lastChangeTime), hand == 0,
                                 protocol_button(def_.actions[k].name, hand == 0), *pressed));
}

harness::io::Reach controller_reach() {
  harness::io::Reach r;
  for (const auto& a : curvlab_action_set().actions) {
    if (a.type == ActionType::Pose) continue;
    for (const auto& path : a.subaction_paths) {
      r.buttons.push_back(protocol_button(a.name, path == kLeftHand));
      r.intents |= controller_intents(r.buttons.back());
    }
  }
  r.kind = harness::io::SourceKind::xr_controller;
  r.continue_phrase = "pull a trigger or press A";
  return r;
}

}  // namespace curvlab::harness::xr
