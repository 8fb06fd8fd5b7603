// The preview sheet's conditions: one per distinct stimulus, every trial
// counted once, block by block in run order; practice apart from the main
// blocks, one per staircase, each showing the value it is rendered at.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/preview.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <set>

namespace {

namespace pr = curvlab::harness::protocol;
using curvlab::harness::runner::preview_conditions;
using curvlab::harness::runner::PreviewCondition;

struct Loaded {
  pr::Protocol protocol;
  pr::Design design;
};

Loaded load(const std::string& name, std::uint64_t participant) {
  auto r = pr::load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name);
  EXPECT_TRUE(r.has_value()) << name;
  const auto design = pr::expand_design(*r, participant);
  return {std::move(r).value(), design};
}

// A condition's shown setting `name`.
std::string row(const PreviewCondition& c, const std::string& name) {
  for (const auto& [n, v] : c.settings)
    if (n == name) return v;
  ADD_FAILURE() << "no row " << name;
  return "";
}

std::size_t counted(const std::vector<curvlab::harness::runner::PreviewCondition>& cs) {
  std::size_t n = 0;
  for (const auto& c : cs)
    for (const auto& [block, trials] : c.trials_per_block) n += trials;
  return n;
}

TEST(PreviewConditions, DemoHasOneConditionPerSpaceAndView) {
  const auto [p, d] = load("demo.toml", 1);
  const auto cs = preview_conditions(p, d);
  ASSERT_EQ(cs.size(), 4u);
  for (const auto& c : cs) {
    ASSERT_EQ(c.trials_per_block.size(), 1u);
    EXPECT_EQ(c.trials_per_block[0].first, "main");
    EXPECT_EQ(c.trials_per_block[0].second, 2u);  // two repetitions
  }
  // Factorial order, the last factor (view) fastest.
  EXPECT_EQ(cs[0].levels, (std::vector<std::pair<std::string, std::string>>{{"space", "E3"}, {"view", "tourist"}}));
  EXPECT_EQ(cs[1].levels, (std::vector<std::pair<std::string, std::string>>{{"space", "E3"}, {"view", "native"}}));
  EXPECT_EQ(cs[3].levels, (std::vector<std::pair<std::string, std::string>>{{"space", "H3"}, {"view", "native"}}));
}

TEST(PreviewConditions, ProposedStudySeparatesStickAndTableBlocksWithEqualLevels) {
  const auto [p, d] = load("proposed_study.toml", 1);
  const auto cs = preview_conditions(p, d);
  EXPECT_EQ(counted(cs), d.trials.size());
  // Stick blocks: 3 spaces × 3 views × 3 stick bends; table blocks the same
  // with table bends; the practice block's 2 views × 3 stick bends in E3 on
  // panels of their own.
  EXPECT_EQ(cs.size(), 54u + 6u);
  // stick_bend = 0, table_bend = 0 in E3, tourist, is shown in the practice
  // block, in a stick block (stick drawn) and in a table block (stick
  // hidden): three panels, the practice one counting practice trials only.
  std::vector<const PreviewCondition*> flat_e3_tourist;
  for (const auto& c : cs) {
    const std::set<std::pair<std::string, std::string>> lv(c.levels.begin(), c.levels.end());
    if (lv == std::set<std::pair<std::string, std::string>>{
                  {"space", "E3"}, {"view", "tourist"}, {"stick_bend", "0"}, {"table_bend", "0"}})
      flat_e3_tourist.push_back(&c);
  }
  ASSERT_EQ(flat_e3_tourist.size(), 3u);
  EXPECT_TRUE(flat_e3_tourist[0]->practice);
  EXPECT_EQ(flat_e3_tourist[0]->trials_per_block,
            (std::vector<std::pair<std::string, std::size_t>>{{"practice", 1}}));
  EXPECT_FALSE(flat_e3_tourist[1]->practice);
  EXPECT_FALSE(flat_e3_tourist[2]->practice);
  // Run order: the block where a condition first appears never goes back.
  std::size_t last = 0;
  for (const auto& c : cs) {
    EXPECT_GE(d.trials[c.first_trial].block_position, last);
    last = d.trials[c.first_trial].block_position;
  }
}

TEST(PreviewConditions, PracticeTrialsAreNeverMergedWithMainBlockTrials) {
  for (const char* name : {"proposed_study.toml", "stick_pse_staircase.toml", "one_eye_vs_two.toml"}) {
    SCOPED_TRACE(name);
    const auto [p, d] = load(name, 1);
    std::set<std::string> practice_blocks;
    for (const auto& b : d.blocks)
      if (b.practice) practice_blocks.insert(b.name);
    ASSERT_FALSE(practice_blocks.empty());
    std::size_t practice_panels = 0;
    for (const auto& c : preview_conditions(p, d)) {
      practice_panels += c.practice ? 1 : 0;
      for (const auto& [block, trials] : c.trials_per_block)
        EXPECT_EQ(practice_blocks.contains(block), c.practice) << block;
    }
    EXPECT_GT(practice_panels, 0u);
  }
}

TEST(PreviewConditions, EachStaircaseHasAPanelShowingItsStartValue) {
  const auto [p, d] = load("stick_pse_staircase.toml", 1);
  const auto cs = preview_conditions(p, d);
  // The practice block's one cell, then 2 spaces × 2 projections × 2
  // staircases, each staircase in file order.
  ASSERT_EQ(cs.size(), 1u + 8u);
  EXPECT_TRUE(cs[0].practice);
  EXPECT_TRUE(cs[0].onset_note.empty());
  EXPECT_NE(row(cs[0], "stick").find("sagitta 0 mm"), std::string::npos) << row(cs[0], "stick");
  for (std::size_t k = 1; k < cs.size(); ++k) {
    SCOPED_TRACE(k);
    const bool convex = k % 2 == 1;
    ASSERT_EQ(cs[k].tracks.size(), 1u);
    EXPECT_EQ(cs[k].tracks[0],
              (std::pair<std::string, std::string>{"staircase", convex ? "from-convex" : "from-concave"}));
    // Rendered at the staircase's start (±0.06 m), and the table says so.
    EXPECT_NE(row(cs[k], "stick").find(convex ? "sagitta 60 mm" : "sagitta -60 mm"), std::string::npos)
        << row(cs[k], "stick");
    const std::string start = convex ? "0.06" : "-0.06";
    EXPECT_NE(cs[k].onset_note.find("stimulus.stick_sagitta_m = " + start), std::string::npos)
        << cs[k].onset_note;
    EXPECT_EQ(cs[k].trials_per_block, (std::vector<std::pair<std::string, std::size_t>>{{"main", 40}}));
  }
}

TEST(PreviewConditions, AnAdjustmentPanelShowsItsFirstTrialsStartValue) {
  const auto [p, d] = load("body_coherence.toml", 1);
  const auto cs = preview_conditions(p, d);
  // One panel per block and walk level, not one per drawn start value.
  ASSERT_EQ(cs.size(), 6u);
  for (const auto& c : cs) {
    const auto& first = d.trials[c.first_trial];
    ASSERT_TRUE(first.adjustment_start.has_value());
    const std::string pose = row(c, "stick pose");
    // The distance shown is the start drawn for the first trial, not the
    // protocol's 0.5 m.
    const double shown = std::stod(pose.substr(pose.find(", ") + 2));
    EXPECT_NEAR(shown, *first.adjustment_start, 1e-12) << pose;
    EXPECT_NE(c.onset_note.find("adjustment start of trial " + std::to_string(first.index)), std::string::npos)
        << c.onset_note;
  }
}

TEST(PreviewConditions, EveryExampleCountsEveryTrialOnce) {
  for (const char* name : {"demo.toml", "proposed_study.toml", "stick_pse_staircase.toml", "one_eye_vs_two.toml",
                           "body_coherence.toml"}) {
    SCOPED_TRACE(name);
    const auto [p, d] = load(name, 2);
    EXPECT_EQ(counted(preview_conditions(p, d)), d.trials.size());
  }
}

}  // namespace
