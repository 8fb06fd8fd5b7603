// Key presses made for the participant in scripted pilots and tests
// (DesktopOptions::key_script): one `KEY [WHEN]` per line, '#' starts a
// comment. WHEN is `PHASE+DELAY_MS` (`response+150`: 150 ms after the next
// response window opens; a page's time counts from when it accepts a key),
// `PHASE` (at once), or a bare DELAY_MS (default 300) after the runner next
// waits for input. A line ending in `repeat` (`2 response+150 repeat`) is a
// standing rule from where the script reaches it on: its key is pressed at
// every start of its phase, and the script goes on past it at once. A line `hand left|right X Y Z [WHEN]` instead puts that
// hand at the lab position (X, Y, Z) metres, by the same timing rule
// (scripted table calibrations: the hand on a corner, then `space`). Parsing,
// checking against a protocol's timeline and playing are separate and pure,
// so the timing rules are tested without a window.
#pragma once

#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/io/phase.hpp"
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
  // The phase the delay counts from (`response+150`); nullopt: the next
  // frame on which the runner waits for input.
  std::optional<harness::io::Phase> phase;
  bool repeat = false;  // a standing rule (needs a phase)
  // A look line: the head turned by (left +, up +) degrees, as the mouse turns it.
  std::optional<glm::dvec2> look_deg;
};

// Parses script text; `origin` names the file in messages. A bad line is a
// bad_input Error "FILE:LINE: what was expected".
harness::Result<std::vector<ScriptedKey>> parse_key_script(const std::string& text, const std::string& origin);
harness::Result<std::vector<ScriptedKey>> load_key_script(const std::string& path);

// A line whose key would land where it cannot do what it is there for: a
// delay longer than the phase it names (the key would fall into the next
// one), an answer key in fixation or the inter-trial interval (an early
// input, dropped), a phase the protocol never shows, an answer pressed after
// the response window of its bare delay. A bad_input Error "FILE:LINE: …"
// naming the phase, its length in the protocol and what was expected; nullopt
// when every line fits.
std::optional<harness::Error> check_key_script(const std::vector<ScriptedKey>& keys, const std::string& origin,
                                               const KeyScriptLimits& limits);

// Plays a script against the runner's overlay. The runner shows it to the
// backend every frame (submit); a key is armed, after the previous key was
// pressed and the frame that took it was shown, on the first frame of the
// phase it names (a page: once the page accepts a key) or, without a phase,
// on the first frame on which the runner waits for input; it is pressed once
// its delay has passed since then. Not thread-safe.
class KeyScriptPlayer {
 public:
  explicit KeyScriptPlayer(std::vector<ScriptedKey> keys) : keys_(std::move(keys)) {}

  // The overlay of the frame just submitted.
  void on_frame(harness::io::Phase phase, bool waiting_for_input, std::int64_t now_ns);
  // The key due at now_ns, if any (at most one per call: the runner sees the
  // effect of each key before the next is armed).
  std::optional<ScriptedKey> due(std::int64_t now_ns);

  // The lines in order are used up (standing rules may still press).
  [[nodiscard]] bool finished() const { return next_ >= keys_.size(); }
  [[nodiscard]] std::size_t pressed() const { return pressed_; }
  // Whether the script has left a page waiting for a key for kRunOutNs, with
  // its lines used up and nobody typing (typed() restarts the wait): a
  // scripted pilot that stopped answering ends then, instead of waiting
  // forever.
  [[nodiscard]] bool ran_out(std::int64_t now_ns) const {
    return finished() && idle_since_ns_ && now_ns - *idle_since_ns_ >= kRunOutNs;
  }
  void typed() { idle_since_ns_.reset(); }
  // The message a session that ran out ends with.
  [[nodiscard]] std::string ran_out_message(const std::string& script, harness::io::Phase page) const;
  static constexpr std::int64_t kRunOutNs = 5'000'000'000;
  // The line of the last key pressed (0: none yet).
  [[nodiscard]] int last_line() const { return last_line_; }

 private:
  struct Rule {
    ScriptedKey key;
    bool pending = false;  // its phase began and it has not been armed for it yet
    std::optional<std::int64_t> armed_at_ns;
  };
  void take_rules();

  std::vector<ScriptedKey> keys_;
  std::size_t next_ = 0;
  std::vector<Rule> rules_;
  std::optional<std::int64_t> armed_at_ns_;
  std::optional<harness::io::Phase> last_phase_;
  bool entered_ = false;  // a phase began (or a page turned) since the last key was armed
  bool taking_ = false;   // a key was just pressed: the next frame shown is the one that took it
  std::optional<std::int64_t> idle_since_ns_;  // a page waits, the script used up
  std::size_t pressed_ = 0;
  int last_line_ = 0;
};

}  // namespace curvlab::harness::desktop
