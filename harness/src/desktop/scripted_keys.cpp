// A key script typed into a display that has no keyboard (desktop.hpp,
// make_scripted_keys): the scripted pilot of a headless run.
#include "key_script.hpp"

#include "curvlab/harness/desktop/desktop.hpp"

#include <iostream>

namespace curvlab::harness::desktop {
namespace {

using harness::io::Overlay;
using harness::io::Signal;

// Owns nothing but the player; borrows the display and the clock, which
// outlive it (cli Devices). Not thread-safe: the frame thread uses it.
class ScriptedKeysImpl final : public ScriptedKeys {
 public:
  ScriptedKeysImpl(harness::io::Display& inner, const harness::io::Clock& clock, std::vector<ScriptedKey> keys,
                   std::string script)
      : inner_(inner), clock_(clock), player_(std::move(keys)), script_(std::move(script)) {}

  [[nodiscard]] harness::io::DisplayInfo info() const override { return inner_.info(); }
  std::optional<harness::io::FrameTiming> begin_frame() override { return inner_.begin_frame(); }
  Signal poll_signal() override { return inner_.poll_signal(); }
  renderer::StereoRig rig(const harness::io::FrameTiming& frame, double ipd_m) override {
    return inner_.rig(frame, ipd_m);
  }
  renderer::FrameStats submit(const renderer::Scene& scene, const renderer::FrameDescription& frame,
                              const Overlay& overlay, bool draw) override {
    player_.on_frame(overlay.phase, overlay.waiting_for_input, clock_.now_ns());
    last_phase_ = overlay.phase;
    return inner_.submit(scene, frame, overlay, draw);
  }
  std::vector<std::string> save_frame(const std::string& stem) override { return inner_.save_frame(stem); }
  harness::io::FrameMirror* mirror() override { return inner_.mirror(); }
  void take_reports(std::vector<harness::io::DisplayReport>& out) override { inner_.take_reports(out); }

  Signal poll(std::vector<harness::io::InputEvent>& out) override {
    if (quit_) return Signal::none;
    const std::int64_t now = clock_.now_ns();
    if (auto key = player_.due(now)) {
      out.push_back(key_input(now, key->name, true, harness::io::SourceKind::script));
      if (key->name == "escape") {  // ends the session, resumable, as the window's key does
        quit_ = true;
        return Signal::quit;
      }
    }
    if (player_.ran_out(now)) {
      std::cerr << "curvlab: " << player_.ran_out_message(script_, last_phase_) << '\n';
      quit_ = true;
      return Signal::quit;
    }
    return Signal::none;
  }
  [[nodiscard]] harness::io::Reach reach() const override {
    harness::io::Reach r = keyboard_reach();
    r.kind = harness::io::SourceKind::script;
    return r;
  }

 private:
  harness::io::Display& inner_;
  const harness::io::Clock& clock_;
  KeyScriptPlayer player_;
  std::string script_;
  harness::io::Phase last_phase_ = harness::io::Phase::iti;
  bool quit_ = false;
};

}  // namespace

harness::Result<std::unique_ptr<ScriptedKeys>> make_scripted_keys(harness::io::Display& inner,
                                                                  const harness::io::Clock& clock,
                                                                  const std::string& script,
                                                                  const std::optional<KeyScriptLimits>& limits) {
  auto loaded = load_key_script(script);
  if (!loaded) return loaded.error();
  for (const auto& k : loaded.value())
    if (k.hand_m || k.look_deg)
      return harness::Error{harness::Error::Kind::usage,
                            script + ":" + std::to_string(k.line) + ": a " + k.name + " line needs a body to move; " +
                                "expected --backend desktop (this run has no keyboard or mouse body, only its "
                                "key script)"};
  if (limits)
    if (auto wrong = check_key_script(loaded.value(), script, *limits)) return *wrong;
  return std::unique_ptr<ScriptedKeys>(new ScriptedKeysImpl(inner, clock, std::move(loaded).value(), script));
}

}  // namespace curvlab::harness::desktop
