// The psi judgement answered by the simulated observer (observer.hpp) with
// a known PSE and slope: after a fixed number of trials its PSE estimate lies
// near the truth for every seed, and its posterior SD is honest about how
// near.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/observer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace pr = curvlab::harness::protocol;
namespace rn = curvlab::harness::runner;

TEST(PsiRecovery, PseEstimateLiesNearTheObserversPseForEverySeed) {
  const auto loaded = pr::load_protocol_text(
      "[protocol]\nname = \"r\"\nversion = \"1\"\n[randomization]\nseed = 5\n"
      "[judgement]\ntype = \"psi\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"convex\"\n"
      "options = [{ value = \"convex\", keys = [\"1\"] }, { value = \"concave\", keys = [\"2\"] }]\n"
      "values = { min = -0.05, max = 0.05, count = 41 }\n"
      "pse = { min = -0.05, max = 0.05, count = 201 }\n"
      "slope = { min = 20.0, max = 2000.0, count = 20 }\n"
      "lapse = 0.02\ntrials = 60\n",
      "r.toml");
  ASSERT_TRUE(loaded.has_value());
  const pr::Judgement& j = loaded->blocks.at(0).judgement;
  const pr::Design d = pr::expand_design(*loaded, 1);
  ASSERT_EQ(d.trials.size(), 60u);

  struct Truth {
    double pse_m, slope_per_m;
  };
  int within_two_sd = 0, runs = 0;
  for (const Truth truth : {Truth{-0.012, 300.0}, Truth{0.02, 150.0}, Truth{0.004, 600.0}}) {
    double squared = 0.0;
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      rn::ObserverParams params;
      params.bias_m = -truth.pse_m;  // P(convex | x) = Φ(slope (x + bias)): the PSE is −bias
      params.slope_per_m = truth.slope_per_m;
      params.lapse = 0.02;
      params.seed = seed;
      rn::SimulatedObserver observer(params);
      auto state = j.type->adaptive_state(j);
      pr::AdaptiveStep last;
      for (const auto& t : d.trials) last = state->record(t, observer.choose(state->value(t), 2, observer.metric_noise_sd_m()) == 0);
      const double error = last.posterior->pse_mean - truth.pse_m;
      SCOPED_TRACE("PSE " + std::to_string(truth.pse_m) + ", slope " + std::to_string(truth.slope_per_m) +
                   ", seed " + std::to_string(seed));
      EXPECT_LT(std::abs(error), 0.004);
      // On a grid the posterior can settle on one point: half the PSE grid's
      // step (0.25 mm) is the least error bar it can honestly give.
      within_two_sd += std::abs(error) <= 2.0 * last.posterior->pse_sd + 0.00025 ? 1 : 0;
      ++runs;
      squared += error * error;
    }
    // Over the seeds the estimate is within 2 mm RMS of the truth.
    EXPECT_LT(std::sqrt(squared / 8.0), 0.002) << truth.pse_m;
  }
  // The posterior SD is a fair error bar: about 95 % of the runs lie within two.
  EXPECT_GE(within_two_sd, runs - 3);
}
