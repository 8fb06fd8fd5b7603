// The simulated observer (DESIGN.md §5): the perception model gives a signed
// perceived quantity (the stick's or the table top's sagitta, metres,
// positive toward the viewer / bulging up); a psychometric response model
// with per-participant bias, slope and lapse turns it into a judgement, and
// a response-time model into key presses on the session clock. The same
// observer answers headless runs, predicts results before a study
// (`curvlab predict`) and makes parameter-recovery tests possible.
//
// Response model, with latent L = s + bias_m + ε, ε ~ N(0, 1/slope_per_m²):
//  - n ordered options (the protocol lists them from the most positive,
//    e.g. convex, to the most negative, e.g. concave): option k is chosen when
//    L lies between cut k−1 and cut k; the n−1 cuts are spaced evenly from
//    +criterion_m to −criterion_m (n = 2: one cut at 0, so
//    P(first) = Φ(slope·(s + bias)); n = 3: cuts at ±criterion_m);
//  - with probability lapse the answer is a uniformly random option;
//  - adjustment: the observer moves the parameter to where L = 0 (solved by
//    bisection on the perceived quantity) and confirms.
#pragma once

#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/result.hpp"

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

enum class ObserverModel {
  perception,  // the perception model: what a Euclidean-born observer would see
  physical,    // the physical stimulus only (as if every space were E3): a null model
  random,      // uniformly random answers
  image,       // the stick's sagitta read from the rendered onset pair (image_observer.hpp);
               // judgements of the table and adjustments answer as `perception`
};
std::string_view to_string(ObserverModel m);
std::optional<ObserverModel> parse_observer_model(std::string_view text);

struct ObserverParams {
  ObserverModel model = ObserverModel::perception;
  double bias_m = 0.0;           // added to the perceived quantity
  double slope_per_m = 300.0;    // 1 / noise SD (300 /m: SD 3.3 mm)
  double lapse = 0.02;           // probability of a random answer
  double criterion_m = 0.006;    // half-width of the "straight" band (3 options)
  double rt_base_ms = 450.0;     // response time: base + exponential
  double rt_mean_extra_ms = 250.0;
  std::uint64_t seed = 1;
};

// Done when every value is in range; otherwise what was expected.
Result<Done> check_observer(const ObserverParams& p);
std::string observer_json(const ObserverParams& p);

// Standard normal CDF.
double normal_cdf(double x);
// A standard normal draw (Box–Muller on the portable uniform draw, so a seed
// gives the same values with every standard library).
double standard_normal(protocol::Engine& rng);

class SimulatedObserver {
 public:
  explicit SimulatedObserver(const ObserverParams& params);
  [[nodiscard]] const ObserverParams& params() const { return params_; }

  // Probability of each of n ordered options for perceived quantity s.
  [[nodiscard]] std::vector<double> choice_probabilities(double s, std::size_t n) const;
  // Draws the chosen option index.
  std::size_t choose(double s, std::size_t n);
  // The value the observer settles on in an adjustment: the root of
  // perceived(x) + bias + ε = 0 on [lo, hi] (an end when there is none).
  double adjust(const std::function<double(double)>& perceived, double lo, double hi);
  // Response time in nanoseconds.
  std::int64_t response_time_ns();
  // A uniform draw in [0, 1) from the observer's stream.
  double uniform();

 private:
  ObserverParams params_;
  protocol::Engine rng_;
};

}  // namespace curvlab::harness::runner
