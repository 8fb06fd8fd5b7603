// Key presses made for the participant in scripted pilots and tests
// (DesktopOptions::key_script): one `KEY [DELAY_MS]` per line, '#' starts a
// comment. Each key is pressed DELAY_MS (default 300) after the runner next
// waits for input. A line `hand left|right X Y Z [DELAY_MS]` instead puts
// that hand at the lab position (X, Y, Z) metres, by the same timing rule
// (scripted table calibrations: the hand on a corner, then `space`). Parsing is separate from playing, and both are pure, so
// the timing rule is tested without a window.
#pragma once

#include "curvlab/harness/result.hpp"

#include <glm/vec3.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::harness::desktop {

struct ScriptedKey {
  std::string name;  // lower-case, as InputEvent names keys ("1", "space", "left"); "hand" for a hand line
  std::int64_t delay_ns = 300'000'000;
  int line = 0;  // in the script file, for messages
  // A hand line: where the hand goes (lab metres), and which hand.
  std::optional<glm::dvec3> hand_m;
  bool left_hand = false;
};

// Parses script text; `origin` names the file in messages. A bad line is a
// bad_input Error "FILE:LINE: what was expected".
harness::Result<std::vector<ScriptedKey>> parse_key_script(const std::string& text, const std::string& origin);
harness::Result<std::vector<ScriptedKey>> load_key_script(const std::string& path);

// Plays a script against the runner's overlay. The runner shows it to the
// backend every frame (submit); a key is armed the first frame, after the
// previous key was pressed, on which the runner waits for input, and is
// pressed once its delay has passed since then. Not thread-safe.
class KeyScriptPlayer {
 public:
  explicit KeyScriptPlayer(std::vector<ScriptedKey> keys) : keys_(std::move(keys)) {}

  // The overlay of the frame just submitted.
  void on_frame(bool waiting_for_input, std::int64_t now_ns);
  // The key due at now_ns, if any (at most one per call: the runner sees the
  // effect of each key before the next is armed).
  std::optional<ScriptedKey> due(std::int64_t now_ns);

  [[nodiscard]] bool finished() const { return next_ >= keys_.size(); }
  [[nodiscard]] std::size_t pressed() const { return next_; }

 private:
  std::vector<ScriptedKey> keys_;
  std::size_t next_ = 0;
  std::optional<std::int64_t> armed_at_ns_;
};

}  // namespace curvlab::harness::desktop
