// `curvlab predict`: what a protocol should find before anyone is tested.
// The simulated observer (observer.hpp; by default the human model, with its
// account in arcseconds: the disparity signal, the threshold, d′, fusion and
// the perceived distance) answers every choice condition of the design;
// participants differ in bias and in the scale of their noise (slope, and
// threshold), drawn from a population; expected response proportions per
// condition are averaged over them. Adaptive blocks (staircases and the
// like) get, per condition and track, the stimulus value the method
// converges on for the mean observer, and whether it lies inside its range.
// Power comes from simulated studies analysed with a paired t-test across
// participants: on the proportion of the first option (e.g. "convex") for
// choice trials, and on the value each condition's adaptive tracks settle
// on (the mean value shown over the second half of its trials, simulated
// trial by trial through the judgement type) for adaptive ones — each study
// drawing its participants from a pool of 3 per study participant (at
// least 60), simulated once through every adaptive condition.
// Conditions are listed in the design's order: blocks as the protocol lists
// them, then each factor's levels as declared, factors in the design's
// order (by name, as `curvlab design` lists them).
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/harness/runner/observer.hpp"
#include "curvlab/harness/runner/percept.hpp"

#include <optional>
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
  double perceived_m = 0.0;  // the mean observer's signed sagitta
  double noise_sd_m = 0.0;   // and the SD of its noise
  // The human model's account (percept.hpp): signal and threshold in
  // arcseconds, d′, fusion, perceived distance.
  std::optional<HumanAccount> human;
  // Judged points a tourist sees only along diverging or parallel lines of
  // sight (stimulus.hpp, diverging_sight_lines): the triangulation model's
  // perceived_m is then ill-conditioned, and a note says so.
  int diverging_points = 0;
  int judged_points = 0;
  std::vector<std::string> options;
  std::vector<double> proportions;  // expected, per option
};

struct PowerEstimate {
  std::string factor, level_a, level_b;
  // What is compared: "P(first option)" (choice trials) or the adaptive
  // tracks' settled value, e.g. "stimulus.stick_sagitta_m".
  std::string measure;
  double predicted_difference = 0.0;  // measure at a − measure at b
  double power = 0.0;
  int simulations = 0;
};

// One staircase of one condition: where the mean observer's staircase
// settles. An m-up/n-down rule converges where a run of n positive answers
// is as likely to come first as a run of m negative ones (Levitt 1971):
// 50 % positive for 1-up/1-down, 70.7 % for 1-up/2-down.
struct StaircasePrediction {
  std::string block;
  std::vector<std::pair<std::string, std::string>> levels;  // factor → level
  std::string judged;      // stick or table
  std::string staircase;   // its name
  std::string parameter;   // the setting it varies
  std::string positive;    // the option that counts as positive
  std::string rule;        // "1-up/1-down", "psi" (protocol::ConvergenceTarget::rule)
  int up = 1, down = 1;
  double min = 0.0, max = 0.0;
  double target_p = 0.5;   // P(positive) the rule converges on
  // The value where the mean observer's P(positive) = target_p; nullopt when
  // there is none in [min, max].
  std::optional<double> target_value;
  double p_at_min = 0.0, p_at_max = 0.0;
  int crossings = 0;  // how often P(positive) crosses target_p in [min, max]
};

struct Prediction {
  int participants = 0;
  std::vector<ConditionPrediction> conditions;
  std::vector<StaircasePrediction> staircases;
  std::vector<PowerEstimate> power;
  std::vector<std::string> notes;
};

Result<Prediction> predict(const protocol::Protocol& p, const PredictOptions& options);
// Only where each adaptive track converges for the mean observer (no
// proportions, no power): cheap enough for `validate`.
std::vector<StaircasePrediction> predict_convergence(const protocol::Protocol& p, const ObserverParams& observer);

// Two-sided p value of Student's t with `df` degrees of freedom.
double student_t_two_sided_p(double t, double df);

}  // namespace curvlab::harness::runner
