#include <curvlab/harness/net/clock_sync.hpp>

namespace curvlab::harness::net {

std::int64_t ClockSample::offset_ns() const {
  // Halved separately so that the sum of two large differences cannot
  // overflow; the remainders put back the half each division dropped.
  const std::int64_t a = t2_ns - t1_ns;
  const std::int64_t b = t3_ns - t4_ns;
  return a / 2 + b / 2 + (a % 2 + b % 2) / 2;
}

std::int64_t ClockSample::round_trip_ns() const { return (t4_ns - t1_ns) - (t3_ns - t2_ns); }

ClockEstimator::ClockEstimator(std::size_t window) : window_(window < 1 ? 1 : window) {}

bool ClockEstimator::add(const ClockSample& s) {
  if (s.t4_ns < s.t1_ns || s.t3_ns < s.t2_ns || s.round_trip_ns() < 0) return false;
  samples_.push_back(s);
  while (samples_.size() > window_) samples_.pop_front();
  return true;
}

ClockEstimate ClockEstimator::estimate() const {
  ClockEstimate e;
  if (samples_.empty()) return e;
  const ClockSample* best = &samples_.front();
  for (const auto& s : samples_)
    if (s.round_trip_ns() <= best->round_trip_ns()) best = &s;  // the latest of equals
  e.valid = true;
  e.offset_ns = best->offset_ns();
  e.round_trip_ns = best->round_trip_ns();
  e.uncertainty_ns = e.round_trip_ns / 2;
  e.at_ns = best->t4_ns;
  e.samples = samples_.size();
  return e;
}

std::int64_t ClockEstimator::to_local_ns(std::int64_t partner_ns) const {
  return partner_ns - estimate().offset_ns;
}

}  // namespace curvlab::harness::net
