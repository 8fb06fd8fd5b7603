// Blocks as a level of the session: a run starts at a block and a position
// within it, as that block's kind counts, never at a bare trial index.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/session.hpp"

#include <gtest/gtest.h>

#include <string>

namespace pr = curvlab::harness::protocol;
namespace rn = curvlab::harness::runner;

namespace {

pr::Design design_of(const std::string& name) {
  auto loaded = pr::load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name + ".toml");
  EXPECT_TRUE(loaded.has_value()) << (loaded ? "" : loaded.error().message);
  return pr::expand_design(*loaded, 3);
}

}  // namespace

TEST(Blocks, EveryTrialResumesInItsOwnBlockAtItsPlaceThere) {
  const pr::Design d = design_of("one_eye_vs_two");
  ASSERT_GE(d.blocks.size(), 2u);
  for (std::size_t i = 0; i < d.trials.size(); ++i) {
    const rn::ResumePoint at = rn::resume_point(d, i);
    const auto& t = d.trials[i];
    EXPECT_EQ(at.block, t.block_position) << "trial " << i;
    EXPECT_EQ(at.position, t.trial_in_block) << "trial " << i;
    EXPECT_EQ(d.blocks[at.block].name, t.block) << "trial " << i;
  }
}

TEST(Blocks, ASessionWithEveryTrialEndedResumesAfterItsLastBlock) {
  const pr::Design d = design_of("one_eye_vs_two");
  const rn::ResumePoint at = rn::resume_point(d, d.trials.size());
  EXPECT_EQ(at.block, d.blocks.size());
  EXPECT_EQ(at.position, 0u);
}

TEST(Blocks, EveryBlockOfTheShippedProtocolsIsOfAKindTheRunnerHas) {
  for (const char* name : {"demo", "one_eye_vs_two", "proposed_study", "body_coherence", "stick_pse_psi",
                           "stick_pse_staircase"}) {
    const pr::Design d = design_of(name);
    for (const auto& b : d.blocks) EXPECT_EQ(b.kind, "trials") << name << ": block " << b.name;
  }
}
