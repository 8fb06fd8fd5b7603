// The simulated observer's response model (observer.hpp): probabilities that
// follow the stated formulas, draws whose frequencies match them, and the
// adjustment's root.
#include "curvlab/harness/runner/observer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

namespace rn = curvlab::harness::runner;

namespace {

rn::ObserverParams params(double bias, double slope, double lapse, double criterion = 0.006) {
  rn::ObserverParams p;
  p.bias_m = bias;
  p.slope_per_m = slope;
  p.lapse = lapse;
  p.criterion_m = criterion;
  p.seed = 7;
  return p;
}

}  // namespace

TEST(Observer, TwoOptionsFollowTheLapsedProbit) {
  const rn::SimulatedObserver o(params(0.004, 200.0, 0.1));
  for (double s : {-0.02, -0.004, 0.0, 0.01}) {
    const auto p = o.choice_probabilities(s, 2, o.metric_noise_sd_m());
    // Φ written out with erf, independently of normal_cdf's erfc.
    const double phi = 0.5 * (1.0 + std::erf(200.0 * (s + 0.004) / std::sqrt(2.0)));
    EXPECT_NEAR(p[0], 0.05 + 0.9 * phi, 1e-12) << "s = " << s;
    EXPECT_NEAR(p[0] + p[1], 1.0, 1e-12);
  }
  // The point of subjective equality sits at −bias.
  EXPECT_NEAR(o.choice_probabilities(-0.004, 2, o.metric_noise_sd_m())[0], 0.5, 1e-12);
}

TEST(Observer, ThreeOptionsHaveAStraightBand) {
  const rn::SimulatedObserver o(params(0.0, 300.0, 0.0, 0.006));
  const auto straight = o.choice_probabilities(0.0, 3, o.metric_noise_sd_m());
  EXPECT_NEAR(straight[0], straight[2], 1e-12);
  EXPECT_NEAR(straight[1], std::erf(300.0 * 0.006 / std::sqrt(2.0)), 1e-12);
  const auto bowed = o.choice_probabilities(0.05, 3, o.metric_noise_sd_m());
  EXPECT_GT(bowed[0], 0.999);  // clearly toward the viewer: "convex"
  const auto away = o.choice_probabilities(-0.05, 3, o.metric_noise_sd_m());
  EXPECT_GT(away[2], 0.999);
  for (const auto& v : {straight, bowed, away}) EXPECT_NEAR(std::accumulate(v.begin(), v.end(), 0.0), 1.0, 1e-12);
}

TEST(Observer, DrawsMatchTheProbabilities) {
  rn::SimulatedObserver o(params(0.0, 250.0, 0.05));
  const double s = 0.004;
  const auto p = o.choice_probabilities(s, 3, o.metric_noise_sd_m());
  const int n = 40000;
  std::array<int, 3> counts{};
  for (int i = 0; i < n; ++i) ++counts[o.choose(s, 3, o.metric_noise_sd_m())];
  for (std::size_t k = 0; k < 3; ++k) {
    const double se = std::sqrt(p[k] * (1.0 - p[k]) / n);
    EXPECT_NEAR(counts[k] / double(n), p[k], 4.5 * se) << "option " << k;
  }
}

TEST(Observer, SameSeedSameAnswers) {
  rn::SimulatedObserver a(params(0.0, 100.0, 0.1));
  rn::SimulatedObserver b(params(0.0, 100.0, 0.1));
  for (int i = 0; i < 200; ++i) {
    ASSERT_EQ(a.choose(0.001 * (i % 7), 3, 0.01), b.choose(0.001 * (i % 7), 3, 0.01));
    ASSERT_EQ(a.response_time_ns(), b.response_time_ns());
  }
}

TEST(Observer, AdjustmentSettlesWhereThePerceivedBowVanishes) {
  // A perceived sagitta that is the physical one plus 0.03 m: the observer
  // without bias or lapse settles near −0.03 m, within a few noise SDs.
  rn::SimulatedObserver o(params(0.0, 1000.0, 0.0));
  for (int i = 0; i < 20; ++i) {
    const double x = o.adjust([](double v) { return v + 0.03; }, -0.1, 0.1, o.metric_noise_sd_m());
    EXPECT_NEAR(x, -0.03, 5.0 / 1000.0);
  }
  // No root in range: the nearer end.
  EXPECT_DOUBLE_EQ(o.adjust([](double v) { return v + 1.0; }, -0.1, 0.1, o.metric_noise_sd_m()), -0.1);
}

TEST(Observer, RejectsImpossibleParameters) {
  EXPECT_FALSE(rn::check_observer(params(0.0, -1.0, 0.0)).has_value());
  EXPECT_FALSE(rn::check_observer(params(0.0, 100.0, 1.5)).has_value());
  EXPECT_TRUE(rn::check_observer(params(0.01, 100.0, 0.02)).has_value());
}

TEST(Observer, ItsEventRoundTripsWithTheHumanModelsLimits) {
  rn::ObserverParams p = params(0.003, 250.0, 0.04);
  p.vision.threshold_arcsec = 45.0;
  p.vision.specific_distance_m = 2.5;
  p.vision.divergence_limit_deg = 0.5;
  const auto back = rn::observer_from_json(rn::observer_json(p));
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->model, rn::ObserverModel::human);
  EXPECT_EQ(back->vision.threshold_arcsec, 45.0);
  EXPECT_EQ(back->vision.specific_distance_m, 2.5);
  EXPECT_EQ(back->vision.divergence_limit_deg, 0.5);
  EXPECT_EQ(back->vision.fusion_arcmin, p.vision.fusion_arcmin);
  EXPECT_EQ(back->bias_m, 0.003);
  EXPECT_EQ(back->seed, 7u);
}

// Sessions stored before the human model name the ideal geometer
// "perception", or no model at all: both resume as triangulation.
TEST(Observer, OlderEventsResumeAsTheIdealGeometer) {
  const auto named = rn::observer_from_json(R"({"model":"perception","bias_m":0.002,"seed":11})");
  ASSERT_TRUE(named) << named.error().message;
  EXPECT_EQ(named->model, rn::ObserverModel::triangulation);
  EXPECT_EQ(named->bias_m, 0.002);
  EXPECT_EQ(named->slope_per_m, 300.0);  // absent: the default
  const auto unnamed = rn::observer_from_json(R"({"seed":3})");
  ASSERT_TRUE(unnamed);
  EXPECT_EQ(unnamed->model, rn::ObserverModel::triangulation);
}

TEST(Observer, DamagedEventsAreRefusedWithWhatIsWrong) {
  const auto unknown = rn::observer_from_json(R"({"model":"oracle"})");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().message.find("'oracle'"), std::string::npos) << unknown.error().message;
  const auto typed = rn::observer_from_json(R"({"model":"human","bias_m":"x"})");
  ASSERT_FALSE(typed);
  EXPECT_NE(typed.error().message.find("wrong type"), std::string::npos) << typed.error().message;
  const auto range = rn::observer_from_json(R"({"model":"human","vision":{"threshold_arcsec":-4}})");
  ASSERT_FALSE(range);
  EXPECT_NE(range.error().message.find("threshold_arcsec"), std::string::npos) << range.error().message;
  EXPECT_FALSE(rn::observer_from_json("[1, 2]"));
}
