// `curvlab predict`: what a protocol should find before anyone is tested.
// The simulated observer (observer.hpp) answers every choice condition of the
// design; participants differ in bias and slope, drawn from a population;
// expected response proportions per condition are averaged over them, and
// the power to detect each factor's effect on the proportion of the first
// option (e.g. "convex") comes from simulated studies analysed with a
// paired t-test across participants.
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/runner/observer.hpp"

#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace curvlab::harness::runner {

struct PredictOptions {
  int participants = 20;
  int simulations = 400;       // simulated studies for the power estimate
  ObserverParams observer;     // the population's mean observer
  double bias_sd_m = 0.004;    // between-participant SD of the bias
  double slope_sd_log = 0.3;   // between-participant SD of log(slope)
  double alpha = 0.05;
  // The effect to test: factor and two of its levels. Empty: every factor,
  // each at the pair of levels with the largest predicted difference.
  std::string factor, level_a, level_b;
};

struct ConditionPrediction {
  std::vector<std::pair<std::string, std::string>> levels;  // factor → level
  std::string judged;                                       // stick or table
  std::int64_t trials_per_participant = 0;
  double perceived_m = 0.0;  // the perception model's signed sagitta
  std::vector<std::string> options;
  std::vector<double> proportions;  // expected, per option
};

struct PowerEstimate {
  std::string factor, level_a, level_b;
  double predicted_difference = 0.0;  // P(first option | a) − P(first option | b)
  double power = 0.0;
  int simulations = 0;
};

struct Prediction {
  int participants = 0;
  std::vector<ConditionPrediction> conditions;
  std::vector<PowerEstimate> power;
  std::vector<std::string> notes;
};

std::variant<Prediction, std::string> predict(const protocol::Protocol& p, const PredictOptions& options);

// Two-sided p value of Student's t with `df` degrees of freedom.
double student_t_two_sided_p(double t, double df);

}  // namespace curvlab::harness::runner
