// Questionnaire instruments: the built-in SSQ scored as Kennedy, Lane,
// Berbaum & Lilienthal (1993) against values worked out by hand, a custom
// instrument's reversed items, sums and means, the page an item is shown
// as, and instruments read from a protocol file.
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/questionnaire.hpp"

#include <gtest/gtest.h>

using namespace curvlab::harness::protocol;

namespace {

using Values = std::vector<std::optional<std::int64_t>>;

Values all(std::int64_t v, std::size_t n = 16) { return Values(n, v); }

double score_of(const std::vector<SubscaleResult>& r, const std::string& name) {
  for (const auto& s : r)
    if (s.name == name && s.score) return *s.score;
  ADD_FAILURE() << "no score for " << name;
  return -1.0;
}

TEST(Ssq, HasTheSixteenSymptomsOnTheZeroToThreeScale) {
  const Instrument& ssq = ssq_instrument();
  ASSERT_EQ(ssq.items.size(), 16u);
  EXPECT_EQ(ssq.items[0].text, "General discomfort");
  EXPECT_EQ(ssq.items[7].text, "Nausea");
  EXPECT_EQ(ssq.items[12].text, "Dizziness with eyes closed");
  EXPECT_EQ(ssq.items[15].text, "Burping");
  ASSERT_EQ(ssq.scale.size(), 4u);
  EXPECT_EQ(ssq.scale[0].value, 0);
  EXPECT_EQ(ssq.scale[3].label, "Severe");
  EXPECT_EQ(ssq.scale[2].key, "2");
  EXPECT_EQ(ssq.scale[2].button, "hid_3");
}

TEST(Ssq, AllSlightScoresAsTheWeightsTimesSevenAndTwentyOne) {
  const auto r = score(ssq_instrument(), all(1));
  ASSERT_EQ(r.size(), 4u);
  EXPECT_NEAR(score_of(r, "nausea"), 66.78, 1e-9);          // 7 × 9.54
  EXPECT_NEAR(score_of(r, "oculomotor"), 53.06, 1e-9);      // 7 × 7.58
  EXPECT_NEAR(score_of(r, "disorientation"), 97.44, 1e-9);  // 7 × 13.92
  EXPECT_NEAR(score_of(r, "total"), 78.54, 1e-9);           // 21 × 3.74
  const auto none = score(ssq_instrument(), all(0));
  for (const auto& s : none) EXPECT_EQ(*s.score, 0.0) << s.name;
}

// Items 1–16 rated 3,0,1,2,0,0,1,3,2,0,1,0,2,1,0,1. By hand, with the items
// of each factor:
//   N: 1,6,7,8,9,15,16 → 3+0+1+3+2+0+1 = 10 → 95.4
//   O: 1,2,3,4,5,9,11  → 3+0+1+2+0+2+1 = 9  → 68.22
//   D: 5,8,10,11,12,13,14 → 0+3+0+1+0+2+1 = 7 → 97.44
//   TS: (10 + 9 + 7) × 3.74 = 97.24
TEST(Ssq, AMixedAnswerVectorScoresAsWorkedOutByHand) {
  const Values v{3, 0, 1, 2, 0, 0, 1, 3, 2, 0, 1, 0, 2, 1, 0, 1};
  const auto r = score(ssq_instrument(), v);
  EXPECT_NEAR(score_of(r, "nausea"), 95.4, 1e-9);
  EXPECT_NEAR(score_of(r, "oculomotor"), 68.22, 1e-9);
  EXPECT_NEAR(score_of(r, "disorientation"), 97.44, 1e-9);
  EXPECT_NEAR(score_of(r, "total"), 97.24, 1e-9);
  EXPECT_EQ(*r[3].raw, 26.0);
  EXPECT_EQ(r[3].items, 21u);
}

TEST(Ssq, AScoreNeedsEveryItemItCounts) {
  Values v = all(1);
  v[9] = std::nullopt;  // Fullness of the head: disorientation only
  const auto r = score(ssq_instrument(), v);
  EXPECT_TRUE(r[0].score.has_value());
  EXPECT_TRUE(r[1].score.has_value());
  EXPECT_FALSE(r[2].score.has_value());
  EXPECT_EQ(r[2].answered, 6u);
  EXPECT_FALSE(r[3].score.has_value());
}

TEST(Instrument, ReversedItemsAreMirroredOnTheScaleAndMeansWeighted) {
  Instrument ins;
  ins.name = "rating";
  ins.items = {{"a", "A", false}, {"b", "B", true}, {"c", "C", false}};
  ins.scale = {{-3, "no", "", ""}, {-2, "", "", ""}, {-1, "", "", ""}, {0, "", "", ""},
               {1, "", "", ""},    {2, "", "", ""},  {3, "yes", "", ""}};
  bind_scale_controls(ins.scale);
  ins.subscales = {{"sum_all", {0, 1, 2}, ScoreRule::sum, 1.0}, {"mean_ab", {0, 1}, ScoreRule::mean, 2.0}};
  // b answered -3 scores +3.
  const auto r = score(ins, {1, -3, 2});
  EXPECT_EQ(*r[0].raw, 6.0);
  EXPECT_EQ(*r[1].raw, 2.0);
  EXPECT_EQ(*r[1].score, 4.0);
  EXPECT_EQ(scored_value(ins, 1, 2), -2);
  // Values outside 0–9 are answered by position: 1 … 7.
  EXPECT_EQ(ins.scale[0].key, "1");
  EXPECT_EQ(ins.scale[6].key, "7");
}

TEST(Instrument, AnItemPageShowsTheTextAndEachPointsKeyAndLabel) {
  Instrument ins = ssq_instrument();
  ins.title.clear();
  EXPECT_EQ(item_page(ins, 1), "Fatigue\n\n0 None   1 Slight   2 Moderate   3 Severe");
}

TEST(Instrument, AProtocolDefinesItsOwnAndBlocksNameThem) {
  const auto r = load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/ssq_play.toml");
  ASSERT_TRUE(r.has_value()) << (r ? std::string() : format_diagnostic(r.error().diagnostics.front()));
  const Protocol& p = *r;
  ASSERT_EQ(p.instruments.size(), 1u);
  const Instrument& presence = p.instruments[0];
  EXPECT_EQ(presence.name, "presence");
  ASSERT_EQ(presence.scale.size(), 7u);
  EXPECT_EQ(presence.scale[0].value, -3);
  EXPECT_EQ(presence.scale[3].label, "Neutral");
  EXPECT_TRUE(presence.items[2].reversed);
  ASSERT_EQ(presence.subscales.size(), 2u);
  EXPECT_EQ(presence.subscales[0].rule, ScoreRule::mean);
  EXPECT_EQ(presence.subscales[0].items, (std::vector<std::size_t>{0, 1, 2}));
  std::vector<std::string> instruments;
  for (const auto& b : p.blocks)
    if (b.kind == "questionnaire") instruments.push_back(b.instrument.name);
  EXPECT_EQ(instruments, (std::vector<std::string>{"ssq", "ssq", "presence"}));
}

}  // namespace
