// Method of adjustment as a pure state machine: the participant nudges one
// parameter (e.g. the stick's sagitta) until the stimulus looks right, then
// confirms. The start value is drawn by the design expander and stored with
// the trial, so a resumed session starts from the same value.
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"

#include <string>
#include <vector>

namespace curvlab::harness::protocol {

// The adjustable range, the steps and the inputs; the parameter it varies is
// the judgement's (Judgement::parameter).
struct AdjustmentSpec {
  double start_min = 0.0;
  double start_max = 0.0;
  double step = 0.0;
  double fine_step = 0.0;  // 0: no fine step
  double min = 0.0;
  double max = 0.0;
  std::vector<std::string> keys_decrease, keys_increase, keys_confirm;
  std::vector<std::string> buttons_decrease, buttons_increase, buttons_confirm;
};

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

// A method-of-adjustment judgement of `parameter` built in code rather than
// read from a protocol (judgements/adjustment.cpp).
Judgement adjustment_judgement(const AdjustmentSpec& spec, std::string parameter);

}  // namespace curvlab::harness::protocol
