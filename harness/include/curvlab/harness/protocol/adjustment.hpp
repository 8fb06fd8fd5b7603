// Method of adjustment as a pure state machine: the participant nudges one
// parameter (e.g. the stick's sagitta) until the stimulus looks right, then
// confirms. The start value is drawn by the design expander and stored with
// the trial, so a resumed session starts from the same value.
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"

namespace curvlab::harness::protocol {

class Adjustment {
 public:
  Adjustment(const AdjustmentSpec& spec, double start);
  [[nodiscard]] double value() const { return value_; }
  [[nodiscard]] int steps() const { return steps_; }
  [[nodiscard]] bool confirmed() const { return confirmed_; }
  // Moves by ±step (or ±fine_step when fine and one is set), clamped to
  // [min, max]. Ignored after confirm().
  void increase(bool fine = false);
  void decrease(bool fine = false);
  void confirm() { confirmed_ = true; }

 private:
  void move(double delta);
  AdjustmentSpec spec_;
  double value_;
  int steps_ = 0;
  bool confirmed_ = false;
};

}  // namespace curvlab::harness::protocol
