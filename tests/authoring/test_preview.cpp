// The preview sheet's conditions: one per distinct stimulus, every trial
// counted once, block by block in run order.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/preview.hpp"

#include <gtest/gtest.h>

#include <numeric>
#include <set>

namespace {

namespace pr = curvlab::harness::protocol;
using curvlab::harness::runner::preview_conditions;

pr::Design design_of(const std::string& name, std::uint64_t participant) {
  auto r = pr::load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name);
  EXPECT_TRUE(r.has_value()) << name;
  return pr::expand_design(*r, participant);
}

std::size_t counted(const std::vector<curvlab::harness::runner::PreviewCondition>& cs) {
  std::size_t n = 0;
  for (const auto& c : cs)
    for (const auto& [block, trials] : c.trials_per_block) n += trials;
  return n;
}

TEST(PreviewConditions, DemoHasOneConditionPerSpaceAndView) {
  const auto d = design_of("demo.toml", 1);
  const auto cs = preview_conditions(d);
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
  const auto d = design_of("proposed_study.toml", 1);
  const auto cs = preview_conditions(d);
  EXPECT_EQ(counted(cs), d.trials.size());
  // Stick blocks: 3 spaces × 3 views × 3 stick bends; table blocks the same
  // with table bends; the practice conditions are stick-block conditions.
  EXPECT_EQ(cs.size(), 54u);
  // stick_bend = 0, table_bend = 0 is shown in a stick block (stick drawn)
  // and in a table block (stick hidden): two panels.
  std::size_t flat_e3_tourist = 0;
  for (const auto& c : cs) {
    const std::set<std::pair<std::string, std::string>> lv(c.levels.begin(), c.levels.end());
    if (lv == std::set<std::pair<std::string, std::string>>{
                  {"space", "E3"}, {"view", "tourist"}, {"stick_bend", "0"}, {"table_bend", "0"}})
      ++flat_e3_tourist;
  }
  EXPECT_EQ(flat_e3_tourist, 2u);
  // Run order: the block where a condition first appears never goes back.
  std::size_t last = 0;
  for (const auto& c : cs) {
    EXPECT_GE(d.trials[c.first_trial].block_position, last);
    last = d.trials[c.first_trial].block_position;
  }
}

TEST(PreviewConditions, EveryExampleCountsEveryTrialOnce) {
  for (const char* name : {"demo.toml", "proposed_study.toml", "stick_pse_staircase.toml", "one_eye_vs_two.toml",
                           "body_coherence.toml"}) {
    SCOPED_TRACE(name);
    const auto d = design_of(name, 2);
    EXPECT_EQ(counted(preview_conditions(d)), d.trials.size());
  }
}

}  // namespace
