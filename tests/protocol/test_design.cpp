// Design expansion: reproducible for a seed, different across seeds, every
// cell the right number of times, blocks counterbalanced by participant.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/latin_square.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/random.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <set>

using namespace curvlab::harness::protocol;

namespace {

Protocol load(const std::string& name) {
  const auto r = load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name);
  if (!r)
    for (const auto& d : r.error().diagnostics) ADD_FAILURE() << format_diagnostic(d);
  return *r;
}

// One string per trial: block and levels, the parts an order is made of.
std::vector<std::string> signature(const Design& d) {
  std::vector<std::string> out;
  for (const auto& t : d.trials) {
    std::string s = t.block;
    for (const auto& [f, l] : t.levels) s += " " + f + "=" + l;
    if (t.staircase) s += " s" + std::to_string(t.staircase->index);
    out.push_back(s);
  }
  return out;
}

std::vector<std::string> block_order(const Design& d) {
  std::vector<std::string> out;
  for (const auto& b : d.blocks) out.push_back(b.name);
  return out;
}

}  // namespace

TEST(Design, SameSeedAndParticipantGiveTheSameTrialList) {
  const auto p = load("proposed_study.toml");
  const auto a = expand_design(p, 5), b = expand_design(p, 5);
  EXPECT_EQ(a.seed, b.seed);
  EXPECT_EQ(signature(a), signature(b));
}

TEST(Design, DifferentSeedsGiveDifferentOrders) {
  auto p = load("proposed_study.toml");
  const auto a = expand_design(p, 1);
  p.seed += 1;
  const auto b = expand_design(p, 1);
  EXPECT_NE(a.seed, b.seed);
  EXPECT_EQ(block_order(a), block_order(b));  // counterbalancing depends only on the participant
  EXPECT_NE(signature(a), signature(b));
  auto sa = signature(a), sb = signature(b);
  std::sort(sa.begin(), sa.end());
  std::sort(sb.begin(), sb.end());
  EXPECT_EQ(sa, sb);  // the same trials, in another order
}

TEST(Design, ParticipantsGetTheirOwnSeedUnlessTurnedOff) {
  auto p = load("demo.toml");
  EXPECT_NE(expand_design(p, 1).seed, expand_design(p, 2).seed);
  EXPECT_NE(signature(expand_design(p, 1)), signature(expand_design(p, 2)));
  p.seed_per_participant = false;
  EXPECT_EQ(expand_design(p, 1).seed, p.seed);
  EXPECT_EQ(signature(expand_design(p, 1)), signature(expand_design(p, 2)));
}

TEST(Design, EveryCellAppearsRepetitionsTimesPerBlock) {
  const auto p = load("proposed_study.toml");
  const auto d = expand_design(p, 3);
  ASSERT_EQ(d.trials.size(), 6u + 6u * 27u);
  std::map<std::string, std::map<std::string, int>> counts;
  for (const auto& t : d.trials) {
    std::string cell;
    for (const auto& [f, l] : t.levels) cell += f + "=" + l + " ";
    ++counts[t.block][cell];
  }
  for (const auto& [block, cells] : counts) {
    SCOPED_TRACE(block);
    EXPECT_EQ(cells.size(), block == "practice" ? 6u : 9u);
    for (const auto& [cell, n] : cells) EXPECT_EQ(n, block == "practice" ? 1 : 3) << cell;
  }
  // Factor levels reach the settings the renderer will use.
  for (const auto& t : d.trials) {
    for (const auto& [f, l] : t.levels) {
      if (f == "space") {
        EXPECT_EQ(std::string(curvlab::geometry::to_string(t.settings.space.kind)), l);
      }
      if (f == "view" && l == "monocular") {
        EXPECT_EQ(t.settings.viewing.eyes, curvlab::renderer::EyeSelection::dominant);
        EXPECT_EQ(t.settings.viewing.projection, curvlab::renderer::Projection::native);
      }
    }
    if (t.block.rfind("table-", 0) == 0) {
      EXPECT_FALSE(t.settings.stimulus.show_stick);
    }
  }
}

TEST(Design, RadiusIsDerivedFromThePhysicalEdge) {
  const auto p = load("proposed_study.toml");
  for (const auto& t : expand_design(p, 1).trials) {
    // The virtual edge equals the physical one: ρ · side_rad = table.edge_m.
    EXPECT_NEAR(t.derived.radius_m * t.derived.side_rad, t.settings.table.edge_m, 1e-12);
    const int want = t.settings.space.kind == curvlab::geometry::SpaceKind::S3   ? 3
                     : t.settings.space.kind == curvlab::geometry::SpaceKind::E3 ? 4
                                                                                  : 5;
    EXPECT_EQ(t.derived.table_sides, want);
  }
}

TEST(Design, ShuffleWithinRepetitionKeepsEachRepetitionComplete) {
  const auto p = load("one_eye_vs_two.toml");
  const auto d = expand_design(p, 2);
  for (const auto& b : d.blocks) {
    if (b.practice) continue;
    // 3 eye conditions per repetition, each once.
    for (std::size_t start = b.first_trial; start < b.first_trial + b.trial_count; start += 3) {
      std::set<std::string> eyes;
      for (std::size_t k = start; k < start + 3; ++k) eyes.insert(d.trials[k].levels[0].second);
      EXPECT_EQ(eyes.size(), 3u);
      EXPECT_EQ(d.trials[start].repetition, d.trials[start + 2].repetition);
    }
  }
}

TEST(Design, PracticeBlocksComeFirstAndBlocksAreCounterbalancedByParticipant) {
  const auto p = load("proposed_study.toml");
  std::vector<std::vector<std::string>> orders;
  for (std::uint64_t participant = 1; participant <= 6; ++participant) {
    const auto d = expand_design(p, participant);
    ASSERT_EQ(d.blocks.size(), 7u);
    EXPECT_EQ(d.blocks[0].name, "practice");
    auto order = block_order(d);
    order.erase(order.begin());
    orders.push_back(order);
    ASSERT_TRUE(d.counterbalance_row.has_value());
    EXPECT_EQ(*d.counterbalance_row, participant - 1);
  }
  // Six participants: every block in every position once (Williams, n = 6).
  for (std::size_t pos = 0; pos < 6; ++pos) {
    std::set<std::string> at;
    for (const auto& o : orders) at.insert(o[pos]);
    EXPECT_EQ(at.size(), 6u) << "position " << pos;
  }
  // Participant 7 starts the cycle again.
  auto seventh = block_order(expand_design(p, 7));
  seventh.erase(seventh.begin());
  EXPECT_EQ(seventh, orders[0]);
}

TEST(Design, ExplicitSquareRowsAreUsedInTurn) {
  const auto p = load("one_eye_vs_two.toml");
  const auto order = [&](std::uint64_t participant) {
    auto o = block_order(expand_design(p, participant));
    o.erase(o.begin());  // practice
    return o;
  };
  EXPECT_EQ(order(1), (std::vector<std::string>{"s3", "h3", "e3"}));
  EXPECT_EQ(order(2), (std::vector<std::string>{"h3", "e3", "s3"}));
  EXPECT_EQ(order(3), (std::vector<std::string>{"e3", "s3", "h3"}));
  EXPECT_EQ(order(4), order(1));
}

TEST(Design, StaircaseBlocksHoldMaxTrialsSlotsPerStaircaseAndCell) {
  const auto p = load("stick_pse_staircase.toml");
  const auto d = expand_design(p, 1);
  std::map<std::pair<std::size_t, int>, int> slots;
  for (const auto& t : d.trials)
    if (t.block == "main") {
      EXPECT_EQ(t.judgement->name(), "staircase");
      ++slots[{t.cell, static_cast<int>(t.staircase.value().index)}];
    }
  EXPECT_EQ(slots.size(), 4u * 2u);
  for (const auto& [key, n] : slots) EXPECT_EQ(n, 40);
  // Interleaved: the first ten slots are not all one staircase of one cell.
  std::set<std::pair<std::size_t, int>> first;
  std::size_t seen = 0;
  for (const auto& t : d.trials)
    if (t.block == "main" && seen++ < 10) first.insert({t.cell, static_cast<int>(t.staircase.value().index)});
  EXPECT_GT(first.size(), 2u);
}

TEST(Design, AdjustmentStartsLieInTheirRangeAndVary) {
  const auto p = load("body_coherence.toml");
  const auto d = expand_design(p, 1);
  std::set<double> starts;
  for (const auto& t : d.trials) {
    ASSERT_TRUE(t.adjustment_start.has_value());
    EXPECT_GE(*t.adjustment_start, 0.3);
    EXPECT_LE(*t.adjustment_start, 0.7);
    starts.insert(*t.adjustment_start);
  }
  EXPECT_EQ(starts.size(), d.trials.size());
  // Block settings fall back to the session's and override it where given.
  for (const auto& t : d.trials)
    EXPECT_EQ(t.settings.tracking, t.block == "naive" ? curvlab::geometry::TrackingAlgorithm::naive
                                                      : curvlab::geometry::TrackingAlgorithm::table_anchored);
}

TEST(Design, BreaksAreMarkedAndCounted) {
  const auto p = load("proposed_study.toml");
  const auto d = expand_design(p, 1);
  std::int64_t timelines = 0;
  int breaks = 0;
  for (const auto& t : d.trials) {
    timelines += t.settings.timeline.total_ms();
    if (t.break_before) {
      ++breaks;
      EXPECT_EQ(t.trial_in_block % 14, 0u);
    }
  }
  EXPECT_EQ(breaks, 6);  // one per 27-trial block, before trial 14
  EXPECT_EQ(d.estimated_duration_ms(), timelines + breaks * 10000);
}

// --- portable randomness ----------------------------------------------------

TEST(Random, EngineIsTheStandardMt19937_64) {
  // The standard fixes the 10000th output of a default-constructed engine.
  Engine e;
  e.discard(9999);
  EXPECT_EQ(e(), 9981545732273789042ULL);
}

TEST(Random, BoundedDrawMatchesA128BitReference) {
  __extension__ typedef unsigned __int128 u128;
  for (std::uint64_t bound : {1ULL, 2ULL, 3ULL, 7ULL, 1000ULL, (1ULL << 63) + 5, ~0ULL}) {
    Engine a(99), b(99);
    for (int i = 0; i < 1000; ++i) {
      // Reference: the same rejection rule, written with a 128-bit product.
      u128 m = static_cast<u128>(b()) * bound;
      if (static_cast<std::uint64_t>(m) < bound) {
        const std::uint64_t threshold = (0 - bound) % bound;
        while (static_cast<std::uint64_t>(m) < threshold) m = static_cast<u128>(b()) * bound;
      }
      ASSERT_EQ(bounded(a, bound), static_cast<std::uint64_t>(m >> 64)) << bound;
    }
  }
}

TEST(Random, BoundedDrawIsUniform) {
  Engine e(2024);
  std::array<int, 6> counts{};
  const int n = 60000;
  for (int i = 0; i < n; ++i) ++counts[bounded(e, 6)];
  double chi2 = 0.0;
  for (int c : counts) chi2 += (c - n / 6.0) * (c - n / 6.0) / (n / 6.0);
  EXPECT_LT(chi2, 20.5);  // p ≈ 0.001 for 5 degrees of freedom
}

TEST(Random, ShuffleGivesEveryPermutationOfThree) {
  Engine e(7);
  std::map<std::vector<int>, int> seen;
  for (int i = 0; i < 6000; ++i) {
    std::vector<int> v{0, 1, 2};
    shuffle(v, e);
    ++seen[v];
  }
  ASSERT_EQ(seen.size(), 6u);
  for (const auto& [perm, n] : seen) EXPECT_NEAR(n, 1000, 150);
}
