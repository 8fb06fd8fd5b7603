// Where a participant's answers come from (DESIGN.md §6): the desktop
// window's keyboard, the headset's controllers, HID devices through their
// mapping files (devices/responses.hpp), and the simulated observer. Each
// source timestamps its inputs on the session clock; the runner maps their
// names to responses through the judgement's options.
#pragma once

#include "curvlab/harness/io/frame.hpp"

#include <vector>

namespace curvlab::harness::io {

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
};

}  // namespace curvlab::harness::io
