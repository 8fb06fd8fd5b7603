#include "curvlab/harness/protocol/staircase.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

namespace curvlab::harness::protocol {

Staircase::Staircase(StaircaseSpec spec) : spec_(std::move(spec)), value_(spec_.start) {
  assert(!spec_.step_sizes.empty() && spec_.up >= 1 && spec_.down >= 1);
}

bool Staircase::finished() const {
  return reversals() >= spec_.stop_reversals || trials_ >= spec_.max_trials;
}

double Staircase::current_step() const {
  const auto k = std::min(reversal_values_.size(), spec_.step_sizes.size() - 1);
  return spec_.step_sizes[k];
}

void Staircase::respond(bool positive) {
  ++trials_;
  int direction = 0;
  if (positive) {
    negative_run_ = 0;
    if (++positive_run_ >= spec_.down) {
      direction = -1;
      positive_run_ = 0;
    }
  } else {
    positive_run_ = 0;
    if (++negative_run_ >= spec_.up) {
      direction = +1;
      negative_run_ = 0;
    }
  }
  if (direction == 0) return;
  // A reversal is a change of direction; its value is the level at which the
  // rule fired (before moving), the usual convention for averaging.
  if (last_direction_ != 0 && direction != last_direction_) reversal_values_.push_back(value_);
  last_direction_ = direction;
  value_ = std::clamp(value_ + direction * current_step(), spec_.min, spec_.max);
}

std::optional<double> Staircase::threshold() const {
  const auto skip = static_cast<std::size_t>(std::max(spec_.discard_reversals, 0));
  if (reversal_values_.size() <= skip) return std::nullopt;
  double sum = 0.0;
  for (std::size_t i = skip; i < reversal_values_.size(); ++i) sum += reversal_values_[i];
  return sum / static_cast<double>(reversal_values_.size() - skip);
}

InterleavedStaircases::InterleavedStaircases(const std::vector<StaircaseSpec>& specs) {
  stairs_.reserve(specs.size());
  for (const auto& s : specs) stairs_.emplace_back(s);
}

bool InterleavedStaircases::finished() const {
  return std::all_of(stairs_.begin(), stairs_.end(),
                     [](const Staircase& s) { return s.finished(); });
}

std::size_t InterleavedStaircases::next(Engine& rng) const {
  std::vector<std::size_t> open;
  for (std::size_t i = 0; i < stairs_.size(); ++i)
    if (!stairs_[i].finished()) open.push_back(i);
  assert(!open.empty());
  return open[static_cast<std::size_t>(bounded(rng, open.size()))];
}

double staircase_target_probability(int up, int down) {
  // A run of n positives comes before a run of m negatives with probability
  // p^(n−1)(1 − q^m) / (p^(n−1) + q^(m−1) − p^(n−1) q^(m−1)), q = 1 − p
  // (Feller, An Introduction to Probability Theory, vol. 1, §VIII.1); it
  // increases with p, and the staircase settles where it is 1/2.
  const auto down_first = [&](double p) {
    const double q = 1.0 - p;
    const double a = std::pow(p, down - 1);
    const double b = std::pow(q, up - 1);
    return a * (1.0 - std::pow(q, up)) / (a + b - a * b);
  };
  double lo = 0.0, hi = 1.0;
  for (int it = 0; it < 200; ++it) {
    const double p = 0.5 * (lo + hi);
    if (down_first(p) < 0.5) lo = p;
    else hi = p;
  }
  return 0.5 * (lo + hi);
}

}  // namespace curvlab::harness::protocol
