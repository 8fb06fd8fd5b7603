// Adaptive staircases as pure state machines: no I/O, no clock, no file format.
// n-up/m-down (Levitt 1971): after `down` consecutive positive responses the
// value steps down, after `up` consecutive negative responses it steps up.
// 1-up/2-down converges on the 70.7 % positive point, 1-up/3-down on 79.4 %,
// 1-up/1-down on 50 % (a point of subjective equality).
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/protocol/random.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::protocol {

// One staircase of an interleaved set (n-up/m-down, Levitt 1971).
struct StaircaseSpec {
  std::string name;
  double start = 0.0;
  int up = 1;    // consecutive negative responses before the value goes up
  int down = 2;  // consecutive positive responses before the value goes down
  std::vector<double> step_sizes;  // step k is used after k reversals; the last repeats
  int stop_reversals = 8;
  int max_trials = 50;
  int discard_reversals = 2;  // reversals left out of the threshold estimate
  double min = 0.0;
  double max = 0.0;
};

class Staircase {
 public:
  explicit Staircase(StaircaseSpec spec);

  [[nodiscard]] double value() const { return value_; }
  [[nodiscard]] bool finished() const;
  [[nodiscard]] int trials() const { return trials_; }
  [[nodiscard]] int reversals() const { return static_cast<int>(reversal_values_.size()); }
  [[nodiscard]] const std::vector<double>& reversal_values() const { return reversal_values_; }
  [[nodiscard]] double current_step() const;
  [[nodiscard]] const StaircaseSpec& spec() const { return spec_; }
  // Records the response to value(); moves the value when the rule fires.
  void respond(bool positive);
  // Mean of the reversal values after the first discard_reversals; nullopt
  // when there are none left.
  [[nodiscard]] std::optional<double> threshold() const;

 private:
  StaircaseSpec spec_;
  double value_;
  int trials_ = 0;
  int positive_run_ = 0;
  int negative_run_ = 0;
  int last_direction_ = 0;  // −1 down, +1 up, 0 none yet
  std::vector<double> reversal_values_;
};

// The P(positive) an up/down staircase settles on: where a run of `down`
// positive answers is as likely to come first as a run of `up` negative ones
// (Levitt 1971): 50 % for 1-up/1-down, 70.7 % for 1-up/2-down.
double staircase_target_probability(int up, int down);

// Several staircases run interleaved: each trial goes to one that has not
// finished, chosen uniformly with the portable draw, so the participant
// cannot follow one track.
class InterleavedStaircases {
 public:
  explicit InterleavedStaircases(const std::vector<StaircaseSpec>& specs);
  [[nodiscard]] bool finished() const;
  // Index of the staircase for the next trial; requires !finished().
  std::size_t next(Engine& rng) const;
  Staircase& at(std::size_t i) { return stairs_.at(i); }
  [[nodiscard]] const Staircase& at(std::size_t i) const { return stairs_.at(i); }
  [[nodiscard]] std::size_t size() const { return stairs_.size(); }

 private:
  std::vector<Staircase> stairs_;
};

}  // namespace curvlab::harness::protocol
