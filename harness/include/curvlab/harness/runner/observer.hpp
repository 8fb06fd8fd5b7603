// The simulated observer (DESIGN.md §5, docs/runner.md "The simulated
// observer"): a model of perception (percept.hpp) gives a signed perceived
// quantity (the stick's or the table top's sagitta, metres, positive toward
// the viewer / bulging up) and the SD of its noise; a psychometric response
// model with per-participant bias and lapse turns it into a judgement, and a
// response-time model into key presses on the session clock. The same
// observer answers headless runs, predicts results before a study
// (`curvlab predict`) and makes parameter-recovery tests possible.
//
// Response model, with latent L = s + bias_m + ε, ε ~ N(0, σ²), σ the
// percept's noise SD (the human model's: a stereo threshold in disparity,
// scaled to metres at the perceived distance; the other models': 1/slope_per_m):
//  - n ordered options (the protocol lists them from the most positive,
//    e.g. convex, to the most negative, e.g. concave): option k is chosen when
//    L lies between cut k−1 and cut k; the n−1 cuts are spaced evenly from
//    +criterion_m to −criterion_m (n = 2: one cut at 0, so
//    P(first) = Φ((s + bias)/σ); n = 3: cuts at ±criterion_m);
//  - with probability lapse the answer is a uniformly random option;
//  - adjustment: the observer moves the parameter to where L = 0 (solved by
//    bisection on the perceived quantity) and confirms.
#pragma once

#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

enum class ObserverModel {
  human,          // a Euclidean-born observer with human limits (geometry/human_vision.hpp)
  triangulation,  // the ideal geometer: sight lines met exactly, noise in metres
                  // (geometry/perception.hpp); "perception" is its former name
  physical,       // the physical stimulus only (as if every space were E3): a null model
  random,         // uniformly random answers
  image,          // the human model applied to the disparities read from the rendered onset
                  // pair (image_observer.hpp); the table and adjustments answer as `human`
};
std::string_view to_string(ObserverModel m);
std::optional<ObserverModel> parse_observer_model(std::string_view text);

struct ObserverParams {
  ObserverModel model = ObserverModel::human;
  geometry::HumanVision vision;  // human and image: the observer's limits
  double bias_m = 0.0;           // added to the perceived quantity
  // A hypothesised adaptation to play: added to the perceived quantity in
  // trials after a play block (0: play changes nothing).
  double adaptation_m = 0.0;
  // 1 / noise SD in metres (300 /m: SD 3.3 mm): the triangulation and
  // physical models' noise, and the human model's when it has no disparity
  // to go on (one eye, or double images).
  double slope_per_m = 300.0;
  double lapse = 0.02;           // probability of a random answer
  double criterion_m = 0.006;    // half-width of the "straight" band (3 options)
  double rt_base_ms = 450.0;     // response time: base + exponential
  double rt_mean_extra_ms = 250.0;
  std::uint64_t seed = 1;
};

// Done when every value is in range; otherwise what was expected.
Result<Done> check_observer(const ObserverParams& p);
// The session's `observer` event (codebook) and back; a field an older event
// lacks keeps its default, an unknown model is an error.
std::string observer_json(const ObserverParams& p);
Result<ObserverParams> observer_from_json(std::string_view json);
// The human model's limits by name (the JSON's and, with dashes, the CLI's
// --observer-NAME), with what each means, in the order docs/runner.md lists them.
struct VisionSetting {
  std::string_view name;
  double geometry::HumanVision::*field;
  std::string_view help;
};
std::span<const VisionSetting> vision_settings();
// Whether the model perceives through geometry/human_vision.hpp.
bool human_limits(ObserverModel m);

// Standard normal CDF.
double normal_cdf(double x);
// A standard normal draw (Box–Muller on the portable uniform draw, so a seed
// gives the same values with every standard library).
double standard_normal(protocol::Engine& rng);

class SimulatedObserver {
 public:
  explicit SimulatedObserver(const ObserverParams& params);
  [[nodiscard]] const ObserverParams& params() const { return params_; }

  // Probability of each of n ordered options for perceived quantity s
  // with noise SD noise_sd_m.
  [[nodiscard]] std::vector<double> choice_probabilities(double s, std::size_t n, double noise_sd_m) const;
  // Draws the chosen option index.
  std::size_t choose(double s, std::size_t n, double noise_sd_m);
  // The value the observer settles on in an adjustment: the root of
  // perceived(x) + bias + ε = 0 on [lo, hi] (an end when there is none).
  double adjust(const std::function<double(double)>& perceived, double lo, double hi, double noise_sd_m);
  // The noise SD in metres of the models without disparity noise.
  [[nodiscard]] double metric_noise_sd_m() const { return 1.0 / params_.slope_per_m; }
  // Response time in nanoseconds.
  std::int64_t response_time_ns();
  // A uniform draw in [0, 1) from the observer's stream.
  double uniform();

 private:
  ObserverParams params_;
  protocol::Engine rng_;
};

}  // namespace curvlab::harness::runner
