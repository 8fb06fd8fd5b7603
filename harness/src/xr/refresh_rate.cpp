#include "curvlab/harness/xr/refresh_rate.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace curvlab::harness::xr {

namespace {

// Rates within half a hertz are the same rate (runtimes report 89.9 for 90).
bool same_rate(double a, double b) { return std::abs(a - b) < 0.5; }

}  // namespace

bool RefreshRatePolicy::should_request() const { return wanted_hz_ && !same_rate(current_hz_, *wanted_hz_); }

std::optional<float> RefreshRatePolicy::choose(const std::vector<float>& offered) const {
  if (!wanted_hz_) return std::nullopt;
  const double want = *wanted_hz_;
  const auto found =
      std::find_if(offered.begin(), offered.end(), [want](float r) { return same_rate(static_cast<double>(r), want); });
  if (found == offered.end()) return std::nullopt;
  return *found;
}

std::string RefreshRatePolicy::not_offered_message(const std::vector<float>& offered) const {
  std::string list;
  for (const float r : offered) list += (list.empty() ? "" : ", ") + std::to_string(std::lround(r));
  std::ostringstream out;
  out << "the headset does not offer the protocol's " << wanted_hz_.value_or(0.0) << " Hz (it offers " << list
      << " Hz); frames run at its " << current_hz_ << " Hz";
  return out.str();
}

void RefreshRatePolicy::requested(float rate, double now_hz) {
  current_hz_ = now_hz;
  requested_hz_ = rate;
}

bool RefreshRatePolicy::on_change(float to_hz) {
  const double to = static_cast<double>(to_hz);
  const bool answer = requested_hz_ > 0.0f && to_hz == requested_hz_ && same_rate(current_hz_, to);
  requested_hz_ = 0.0f;
  if (answer) return true;
  current_hz_ = to;
  return false;
}

}  // namespace curvlab::harness::xr
