#include "curvlab/harness/protocol/adjustment.hpp"

#include <algorithm>

namespace curvlab::harness::protocol {

Adjustment::Adjustment(const AdjustmentSpec& spec, double start)
    : spec_(spec), value_(std::clamp(start, spec.min, spec.max)) {}

void Adjustment::increase(bool fine) {
  move(fine && spec_.fine_step > 0.0 ? spec_.fine_step : spec_.step);
}

void Adjustment::decrease(bool fine) {
  move(-(fine && spec_.fine_step > 0.0 ? spec_.fine_step : spec_.step));
}

void Adjustment::move(double delta) {
  if (confirmed_) return;
  value_ = std::clamp(value_ + delta, spec_.min, spec_.max);
  ++steps_;
}

}  // namespace curvlab::harness::protocol
