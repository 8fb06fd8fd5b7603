// `curvlab predict`: Student's t against tabled values, and the paper's
// study predicted from the perception model, and where staircases converge.
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/staircase.hpp"
#include "curvlab/harness/runner/predict.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

namespace {

// A shipped protocol, loaded.
pr::Protocol example(const std::string& name) {
  auto loaded = pr::load_protocol_file(CURVLAB_SOURCE_DIR "/protocols/" + name + ".toml");
  if (!loaded) ADD_FAILURE() << name << " does not load";
  return loaded ? std::move(*loaded) : pr::Protocol{};
}

// The level a staircase prediction's condition sets for a factor.
std::string level_of_track(const rn::StaircasePrediction& sp, const std::string& factor) {
  for (const auto& [n, l] : sp.levels)
    if (n == factor) return l;
  return std::string();
}

// The level a condition sets for a factor ("" if none).
std::string level(const rn::ConditionPrediction& c, const std::string& factor) {
  for (const auto& [n, l] : c.levels)
    if (n == factor) return l;
  return std::string();
}

// The proposed study predicted for `participants` over `simulations` studies.
rn::Prediction predict_proposed_study(int participants, int simulations,
                                      rn::ObserverModel model = rn::ObserverModel::human) {
  rn::PredictOptions o;
  o.participants = participants;
  o.simulations = simulations;
  o.observer.model = model;
  auto r = rn::predict(example("proposed_study"), o);
  if (!r.has_value()) {
    ADD_FAILURE() << r.error().message;
    return {};
  }
  return std::move(r).value();
}

}  // namespace

TEST(Predict, StudentTMatchesTables) {
  // Two-sided critical values (e.g. Abramowitz & Stegun, table 26.10).
  EXPECT_NEAR(rn::student_t_two_sided_p(2.228138852, 10.0), 0.05, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(2.093024054, 19.0), 0.05, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(3.169272673, 10.0), 0.01, 1e-8);
  EXPECT_NEAR(rn::student_t_two_sided_p(1.0, 1.0), 0.5, 1e-12);  // Cauchy
  EXPECT_NEAR(rn::student_t_two_sided_p(0.0, 5.0), 1.0, 1e-12);
}

TEST(Predict, TheProposedStudyFollowsTheHumanModel) {
  const rn::Prediction pred = predict_proposed_study(12, 100);
  int checked = 0;
  for (const auto& c : pred.conditions) {
    if (c.judged != "stick" || level(c, "stick_bend") != "0") continue;
    const auto space = level(c, "space");
    const auto view = level(c, "view");
    ASSERT_EQ(c.options, (std::vector<std::string>{"convex", "straight", "concave"}));
    if (view == "monocular") {
      EXPECT_FALSE(c.human.has_value()) << "one eye: no disparity to account for";
      EXPECT_GT(c.proportions[1], 0.6) << space << " monocular looks straight";
      ++checked;
      continue;
    }
    ASSERT_TRUE(c.human.has_value()) << space << " " << view;
    EXPECT_TRUE(c.human->fused) << space << " " << view;
    EXPECT_TRUE(std::isfinite(c.perceived_m)) << space << " " << view;
    if (space == "H3") {
      EXPECT_GT(c.proportions[0], 0.9) << "H3 " << view << " bows toward the viewer";
    } else if (space == "S3") {
      // Tourist: the stick lies on the quarter-circumference sphere, all at
      // zero disparity — seen at one vergence, bowed away.
      EXPECT_GT(c.proportions[2], 0.9) << "S3 " << view << " bows away";
    } else {
      EXPECT_GT(c.proportions[1], 0.6) << "E3 " << view << " looks straight";
      // The stick's middle at the specific distance (1 m): seen where it is.
      EXPECT_NEAR(c.human->perceived_distance_m, 1.0, 0.02);
      EXPECT_NEAR(c.human->d_prime, 0.0, 0.05);
    }
    ++checked;
  }
  EXPECT_EQ(checked, 9);
  // A catch-trial bend of 2 cm at 1 m in E3: about 300 arcsec of relative
  // disparity, ten thresholds.
  int catch_trials = 0;
  for (const auto& c : pred.conditions)
    if (c.judged == "stick" && level(c, "space") == "E3" && level(c, "view") == "tourist" &&
        level(c, "stick_bend") == "0.02") {
      ++catch_trials;
      ASSERT_TRUE(c.human.has_value());
      EXPECT_NEAR(c.human->signal_arcsec, 0.063 * 0.02 / 1.0 * 206264.8, 40.0);
      EXPECT_NEAR(c.human->threshold_arcsec, 30.0, 1e-9);
      EXPECT_GT(c.proportions[0], 0.95);
    }
  EXPECT_EQ(catch_trials, 1) << "the E3 tourist catch-trial condition was not predicted";
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

// Conditions come out in the design's order: blocks as listed, then each
// factor's levels as declared, factors in the design's order (by name).
TEST(Predict, ConditionsComeInTheProtocolsOrder) {
  const rn::Prediction pred = predict_proposed_study(2, 2);
  const std::vector<std::string> spaces{"S3", "E3", "H3"}, views{"tourist", "native", "monocular"},
      bends{"-0.02", "0", "0.02"}, table_bends{"-0.03", "0", "0.03"};
  const auto index = [](const std::vector<std::string>& v, const std::string& x) {
    return static_cast<int>(std::find(v.begin(), v.end(), x) - v.begin());
  };
  std::vector<std::array<int, 5>> keys;
  for (const auto& c : pred.conditions)
    keys.push_back({c.judged == "stick" ? 0 : 1, index(spaces, level(c, "space")), index(bends, level(c, "stick_bend")),
                    index(table_bends, level(c, "table_bend")), index(views, level(c, "view"))});
  ASSERT_EQ(keys.size(), 54u);
  EXPECT_TRUE(std::is_sorted(keys.begin(), keys.end()));
  EXPECT_EQ(level(pred.conditions.front(), "space"), "S3");
  EXPECT_EQ(level(pred.conditions.front(), "view"), "tourist");
}

TEST(Predict, ConditionsSeenAlongDivergingSightLinesAreNamed) {
  // The ideal geometer (triangulation): the proposed study's S3 radius comes from its 1 m table edge
  // (ρ = 0.637 m), so the stick 1 m ahead lies just beyond the quarter
  // circumference ρπ/2 = 1.0 m: in the tourist view the eyes' lines of sight
  // to it diverge. Those conditions, and only those, carry the count and a
  // note; native and monocular views and the other spaces never diverge.
  const rn::Prediction pred = predict_proposed_study(2, 2, rn::ObserverModel::triangulation);
  int flagged = 0;
  for (const auto& c : pred.conditions) {
    const std::string space = level(c, "space"), view = level(c, "view");
    if (space == "S3" && view == "tourist" && c.judged == "stick") {
      EXPECT_EQ(c.diverging_points, 3);
      EXPECT_EQ(c.judged_points, 3);
    }
    if (space != "S3" || view != "tourist") {
      EXPECT_EQ(c.diverging_points, 0) << space << " " << view;
    }
    flagged += c.diverging_points > 0 ? 1 : 0;
  }
  EXPECT_GE(flagged, 3);
  int notes = 0;
  for (const auto& n : pred.notes)
    if (n.find("diverging") != std::string::npos) {
      EXPECT_NE(n.find("space=S3"), std::string::npos) << n;
      EXPECT_NE(n.find("view=tourist"), std::string::npos) << n;
      ++notes;
    }
  EXPECT_EQ(notes, flagged);
}

// Levitt's convergence points: 1-up/n-down where P^n = 1/2, and the
// mirror image for m-up/1-down.
TEST(Predict, StaircaseTargetsAreLevittsConvergencePoints) {
  EXPECT_NEAR(pr::staircase_target_probability(1, 1), 0.5, 1e-12);
  EXPECT_NEAR(pr::staircase_target_probability(1, 2), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(pr::staircase_target_probability(1, 3), std::cbrt(0.5), 1e-12);
  EXPECT_NEAR(pr::staircase_target_probability(2, 1), 1.0 - std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(pr::staircase_target_probability(2, 2), 0.5, 1e-12);
}

namespace {

// z with Φ(z) = p, by bisection on erfc (independent of the observer code).
double normal_quantile(double p) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (0.5 * std::erfc(-mid / std::sqrt(2.0)) < p) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = 0; (at = text.find(from, at)) != std::string::npos; at += to.size())
    text.replace(at, from.size(), to);
  return text;
}

std::string staircase_protocol_text(int down) {
  std::ifstream in(CURVLAB_SOURCE_DIR "/protocols/stick_pse_staircase.toml");
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  return replace_all(text, "down = 1\n", "down = " + std::to_string(down) + "\n");
}

}  // namespace

// With the physical observer (it sees the bend as built) the value a
// staircase converges on has a closed form: the bend b where
// λ/2 + (1 − λ)·Φ(k·(b + bias)) equals the rule's target probability.
TEST(Predict, PhysicalObserverStaircasesConvergeOnTheClosedForm) {
  for (int down : {1, 2}) {
    auto loaded = curvlab::harness::protocol::load_protocol_text(staircase_protocol_text(down), "pse.toml");
    ASSERT_TRUE(loaded.has_value());
    rn::PredictOptions o;
    o.observer.model = rn::ObserverModel::physical;
    o.observer.bias_m = 0.01;
    o.observer.slope_per_m = 250.0;
    o.observer.lapse = 0.04;
    auto r = rn::predict(*loaded, o);
    ASSERT_TRUE(r.has_value()) << r.error().message;
    const auto& pred = r.value();
    ASSERT_EQ(pred.staircases.size(), 8u);  // 2 spaces × 2 projections × 2 staircases
    const double target = down == 1 ? 0.5 : std::sqrt(0.5);
    const double expected = normal_quantile((target - 0.02) / 0.96) / 250.0 - 0.01;
    for (const auto& sp : pred.staircases) {
      EXPECT_NEAR(sp.target_p, target, 1e-12);
      ASSERT_TRUE(sp.target_value.has_value()) << sp.staircase;
      EXPECT_NEAR(*sp.target_value, expected, 1e-7) << "down " << down;
      EXPECT_EQ(sp.crossings, 1);
    }
  }
}

// The shipped PSE protocol: every staircase converges inside its range, on
// a monotone judgement, where the ideal geometer says it should.
TEST(Predict, TheStickPseStaircasesConvergeInsideTheirRanges) {
  auto loaded = curvlab::harness::protocol::load_protocol_file(CURVLAB_SOURCE_DIR "/protocols/stick_pse_staircase.toml");
  ASSERT_TRUE(loaded.has_value());
  rn::PredictOptions geometer;
  geometer.observer.model = rn::ObserverModel::triangulation;
  auto r = rn::predict(*loaded, geometer);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  const auto& pred = r.value();
  ASSERT_EQ(pred.staircases.size(), 8u);
  EXPECT_TRUE(pred.notes.empty()) << pred.notes.front();
  for (const auto& sp : pred.staircases) {
    std::string space, projection;
    for (const auto& [f, l] : sp.levels) (f == "space" ? space : projection) = l;
    ASSERT_TRUE(sp.target_value.has_value()) << space << ' ' << projection;
    EXPECT_EQ(sp.crossings, 1) << space << ' ' << projection;
    if (projection == "tourist") EXPECT_NEAR(*sp.target_value, 0.0, 0.002) << "true optics: straight looks straight";
    else if (space == "H3") EXPECT_LT(*sp.target_value, -0.02) << "H3 native: a stick bent away looks straight";
    else EXPECT_GT(*sp.target_value, 0.05) << "S3 native: a stick bent toward the viewer looks straight";
  }
}

// A range the judgement never crosses is reported with what to do.
TEST(Predict, AStaircaseRangeThatMissesTheTargetIsReported) {
  const std::string text =
      replace_all(replace_all(staircase_protocol_text(1), "min = -0.15", "min = 0.005"), "start = -0.06", "start = 0.01");
  auto loaded = curvlab::harness::protocol::load_protocol_text(text, "narrow.toml");
  ASSERT_TRUE(loaded.has_value()) << curvlab::harness::protocol::format_diagnostic(loaded.error().diagnostics.at(0));
  rn::PredictOptions geometer;
  geometer.observer.model = rn::ObserverModel::triangulation;
  auto r = rn::predict(*loaded, geometer);
  ASSERT_TRUE(r.has_value());
  const auto& pred = r.value();
  int missing = 0;
  for (const auto& sp : pred.staircases) missing += sp.target_value ? 0 : 1;
  EXPECT_EQ(missing, 6);  // everything but S3 native, whose target is above 0.005
  ASSERT_EQ(pred.notes.size(), 6u);
  EXPECT_NE(pred.notes[0].find("outside [0.005, 0.15]"), std::string::npos) << pred.notes[0];
  EXPECT_NE(pred.notes[0].find("widen the range"), std::string::npos) << pred.notes[0];
}

// The human model on the same staircases: every track converges inside its
// range; the frontal-plane distortion of a metre-long stick half a metre
// away (its ends 45° off) moves every PSE toward concave bends, H3's further
// than S3's.
TEST(Predict, HumanStaircasesConvergeInsideTheirRangesAndSeparateTheSpaces) {
  rn::PredictOptions o;
  o.participants = 8;
  o.simulations = 60;
  auto r = rn::predict(example("stick_pse_staircase"), o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  const auto& pred = r.value();
  EXPECT_TRUE(pred.notes.empty()) << pred.notes.front();
  double s3 = 0.0, h3 = 0.0;
  for (const auto& sp : pred.staircases) {
    ASSERT_TRUE(sp.target_value.has_value()) << sp.staircase;
    EXPECT_EQ(sp.crossings, 1);
    EXPECT_LT(*sp.target_value, 0.0);
    (level_of_track(sp, "space") == "H3" ? h3 : s3) += *sp.target_value / 4.0;
  }
  EXPECT_LT(h3, s3 - 0.02);
  // Power on the settled values, simulated trial by trial.
  bool space_power = false;
  for (const auto& pe : pred.power)
    if (pe.factor == "space") {
      space_power = true;
      EXPECT_EQ(pe.measure, "stimulus.stick_sagitta_m");
      EXPECT_NEAR(pe.predicted_difference, h3 - s3, 0.02);
      EXPECT_GT(pe.power, 0.9);
    }
  EXPECT_TRUE(space_power);
}

// --effect is honoured for adaptive designs, and refused (a usage error)
// where no trials can answer it.
TEST(Predict, AnEffectOnStaircasesIsTestedOrRefused) {
  const pr::Protocol protocol = example("stick_pse_staircase");
  rn::PredictOptions o;
  o.participants = 6;
  o.simulations = 20;
  o.factor = "projection";
  o.level_a = "native";
  o.level_b = "tourist";
  auto r = rn::predict(protocol, o);
  ASSERT_TRUE(r.has_value()) << r.error().message;
  ASSERT_EQ(r->power.size(), 1u);
  EXPECT_EQ(r->power[0].factor, "projection");
  EXPECT_EQ(r->power[0].level_a, "native");
  EXPECT_EQ(r->power[0].measure, "stimulus.stick_sagitta_m");
  o.level_b = "sideways";
  auto refused = rn::predict(protocol, o);
  ASSERT_FALSE(refused.has_value());
  EXPECT_EQ(refused.error().kind, curvlab::harness::Error::Kind::usage);
  EXPECT_NE(refused.error().message.find("\"sideways\""), std::string::npos) << refused.error().message;
}

// Notes are whole sentences, however long the names in them.
TEST(Predict, LongNotesAreNotCutShort) {
  const std::string name(300, 'b');
  std::string text = replace_all(replace_all(staircase_protocol_text(1), "min = -0.15", "min = 0.005"), "start = -0.06",
                                 "start = 0.01");
  text = replace_all(text, "[[judgement.staircases]]\nname = \"from-convex\"",
                     "[[judgement.staircases]]\nname = \"" + name + "\"");
  auto loaded = curvlab::harness::protocol::load_protocol_text(text, "long.toml");
  ASSERT_TRUE(loaded.has_value()) << curvlab::harness::protocol::format_diagnostic(loaded.error().diagnostics.at(0));
  rn::PredictOptions geometer;
  geometer.observer.model = rn::ObserverModel::triangulation;
  auto r = rn::predict(*loaded, geometer);
  ASSERT_TRUE(r.has_value());
  bool long_note = false;
  for (const auto& n : r->notes) {
    EXPECT_TRUE(n.ends_with("widen the range or change the stimulus")) << n;
    long_note = long_note || n.find(name) != std::string::npos;
  }
  EXPECT_TRUE(long_note);
}
