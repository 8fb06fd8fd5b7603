// Where a participant's answers come from (DESIGN.md §6): the desktop
// window's keyboard, the headset's controllers, HID devices through their
// mapping files (devices/responses.hpp), and the simulated observer. Each
// source timestamps its inputs on the session clock and says what each means
// (input.hpp: its intents); the runner finds the answer a control gives
// through the judgement's options (answer_index).
#pragma once

#include "curvlab/harness/io/frame.hpp"

#include <algorithm>
#include <string>
#include <vector>

namespace curvlab::harness::io {

// What a source can press: the participant is told how to continue a page
// from it, and a protocol whose answers no source of the session can give is
// refused before anything is written.
struct Reach {
  SourceKind kind = SourceKind::keyboard;
  // Every intent one of its controls has (a page's continue, the table
  // calibration's steps): the participant is told only of steps a source
  // at hand can take.
  Intents intents;
  bool every_key = false;            // a keyboard: every key name
  std::vector<std::string> buttons;  // the button names it gives
  bool simulated = false;            // presses whatever the judgement asks (the simulated observer)
  // How a person continues a page with it ("press space"); "" none.
  std::string continue_phrase;

  [[nodiscard]] bool gives_key(const std::string&) const { return every_key || simulated; }
  [[nodiscard]] bool gives_button(const std::string& name) const {
    return simulated || std::find(buttons.begin(), buttons.end(), name) != buttons.end();
  }
};

class ResponseSource {
 public:
  virtual ~ResponseSource() = default;
  ResponseSource() = default;
  ResponseSource(const ResponseSource&) = delete;
  ResponseSource& operator=(const ResponseSource&) = delete;
  // Appends the inputs that arrived since the last call, oldest first, and
  // returns what the source asks of the session (a pause key, a device
  // unplugged). May throw DeviceFailure.
  virtual Signal poll(std::vector<InputEvent>& out) = 0;
  // What it can press (above); nothing by default.
  [[nodiscard]] virtual Reach reach() const { return {}; }
};

}  // namespace curvlab::harness::io
