// `curvlab predict`: Student's t against tabled values, and the paper's
// study predicted from the perception model.
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/predict.hpp"

#include <gtest/gtest.h>

namespace rn = curvlab::harness::runner;

TEST(Predict, StudentTMatchesTables) {
  // Two-sided critical values (e.g. Abramowitz & Stegun, table 26.10).
  EXPECT_NEAR(rn::student_t_two_sided_p(2.228138852, 10.0), 0.05, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(2.093024054, 19.0), 0.05, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(3.169272673, 10.0), 0.01, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(1.0, 1.0), 0.5, 1e-12);  // Cauchy
  EXPECT_NEAR(rn::student_t_two_sided_p(0.0, 5.0), 1.0, 1e-12);
}

TEST(Predict, TheProposedStudyFollowsThePerceptionModel) {
  auto loaded = curvlab::harness::protocol::load_protocol_file(CURVLAB_SOURCE_DIR "/protocols/proposed_study.toml");
  ASSERT_TRUE(loaded.ok());
  rn::PredictOptions o;
  o.participants = 12;
  o.simulations = 100;
  auto r = rn::predict(*loaded.protocol, o);
  ASSERT_TRUE(std::holds_alternative<rn::Prediction>(r)) << std::get<std::string>(r);
  const auto& pred = std::get<rn::Prediction>(r);
  auto level = [](const rn::ConditionPrediction& c, const std::string& f) {
    for (const auto& [n, l] : c.levels)
      if (n == f) return l;
    return std::string();
  };
  int checked = 0;
  for (const auto& c : pred.conditions) {
    if (c.judged != "stick" || level(c, "stick_bend") != "0") continue;
    const auto space = level(c, "space");
    const auto view = level(c, "view");
    ASSERT_EQ(c.options, (std::vector<std::string>{"convex", "straight", "concave"}));
    if (view == "native" && space == "H3") {
      EXPECT_GT(c.proportions[0], 0.9) << "H3 native bows toward the viewer";
    } else if (view == "native" && space == "S3") {
      EXPECT_GT(c.proportions[2], 0.9) << "S3 native bows away";
    } else if (view != "native") {
      // Mostly straight: a majority, though biased participants of the
      // population (SD 4 mm) push some answers out of the straight band.
      EXPECT_GT(c.proportions[1], 0.6) << space << " " << view << " looks straight";
    }
    ++checked;
  }
  EXPECT_EQ(checked, 9);
  bool view_power = false;
  for (const auto& pe : pred.power) {
    EXPECT_GE(pe.power, 0.0);
    EXPECT_LE(pe.power, 1.0);
    if (pe.factor == "view") {
      view_power = true;
      EXPECT_GT(pe.power, 0.8);  // a large effect with 12 participants
    }
  }
  EXPECT_TRUE(view_power);
}
