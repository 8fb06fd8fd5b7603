// The PSE staircases run by the session runner, answered by the simulated
// observer, settle where `curvlab predict` says they will: the runner's
// staircase logic, the observer's response model and the prediction's
// root finding agree.
#include "in_process.hpp"

#include "curvlab/harness/runner/predict.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

namespace {

using curvlab::testing::query;
namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

}  // namespace

TEST(StaircaseRun, PseStaircasesSettleWherePredicted) {
  const auto out = curvlab::testing::run_protocol("stick_pse_staircase", "pse", "", true,
                                                  [](curvlab::testing::ScriptedDevices&) {});
  ASSERT_FALSE(out.db.empty());
  EXPECT_EQ(out.summary.status, curvlab::harness::data::SessionStatus::completed);

  auto loaded = pr::load_protocol_file(CURVLAB_SOURCE_DIR "/protocols/stick_pse_staircase.toml");
  ASSERT_TRUE(loaded.has_value());
  auto predicted = rn::predict(*loaded, rn::PredictOptions{});
  ASSERT_TRUE(predicted.has_value());
  std::map<std::string, double> expected;  // "space projection" → value
  for (const auto& sp : predicted.value().staircases) {
    std::string space, projection;
    for (const auto& [f, l] : sp.levels) (f == "space" ? space : projection) = l;
    ASSERT_TRUE(sp.target_value.has_value());
    expected[space + " " + projection] = *sp.target_value;
  }
  ASSERT_EQ(expected.size(), 4u);

  // Per condition: the mean intensity at the reversals after the first three
  // (the protocol's discard_reversals), both staircases pooled.
  const auto rows = query(out.db,
                          "SELECT json_extract(t.conditions, '$.space') || ' ' || "
                          "json_extract(t.conditions, '$.projection'), st.staircase, st.intensity, "
                          "st.is_reversal FROM staircase_steps st JOIN trials t ON t.trial_id = st.trial_id "
                          "ORDER BY st.staircase, st.step_index");
  std::map<std::string, int> reversals_seen;
  std::map<std::string, std::pair<double, int>> pooled;
  for (const auto& r : rows) {
    if (r[3] != "1") continue;
    if (++reversals_seen[r[1]] <= 3) continue;
    pooled[r[0]].first += std::stod(r[2]);
    ++pooled[r[0]].second;
  }
  ASSERT_EQ(pooled.size(), 4u);
  for (const auto& [condition, sum] : pooled) {
    ASSERT_GE(sum.second, 6) << condition;
    const double estimate = sum.first / sum.second;
    // Observer noise SD 3.3 mm, final step 2 mm, about a dozen reversals.
    EXPECT_NEAR(estimate, expected.at(condition), 0.006) << condition;
  }
  // And the spaces differ the way the human model says: a straight stick
  // looks more bowed toward the viewer in H3 than in S3, so H3's PSE is bent
  // further away, in both projections.
  const auto mean = [&](const std::string& c) { return pooled.at(c).first / pooled.at(c).second; };
  EXPECT_LT(mean("H3 native"), mean("S3 native") - 0.02);
  EXPECT_LT(mean("H3 tourist"), mean("S3 tourist") - 0.02);
}
