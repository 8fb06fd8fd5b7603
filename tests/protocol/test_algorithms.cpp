// The pure algorithms: Williams squares, staircases against a simulated
// responder, method-of-adjustment state.
#include "curvlab/harness/protocol/adjustment.hpp"
#include "curvlab/harness/protocol/latin_square.hpp"
#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/protocol/staircase.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

using namespace curvlab::harness::protocol;

TEST(Williams, EvenOrderIsLatinAndBalancedForCarryover) {
  for (std::size_t n : {2u, 4u, 6u, 8u, 10u}) {
    SCOPED_TRACE(n);
    const Square sq = williams_design(n);
    ASSERT_EQ(sq.size(), n);
    EXPECT_TRUE(check_latin(sq, n));
    // Every ordered pair (a then b, a ≠ b) is adjacent in exactly one row.
    std::map<std::pair<std::size_t, std::size_t>, int> pairs;
    for (const auto& row : sq)
      for (std::size_t c = 0; c + 1 < n; ++c) ++pairs[{row[c], row[c + 1]}];
    EXPECT_EQ(pairs.size(), n * (n - 1));
    for (const auto& [pair, count] : pairs) EXPECT_EQ(count, 1);
  }
}

TEST(Williams, OddOrderNeedsTheMirrorAndThenBalances) {
  for (std::size_t n : {3u, 5u, 7u}) {
    SCOPED_TRACE(n);
    const Square sq = williams_design(n);
    ASSERT_EQ(sq.size(), 2 * n);
    EXPECT_TRUE(check_latin(sq, n));
    std::map<std::pair<std::size_t, std::size_t>, int> pairs;
    for (const auto& row : sq)
      for (std::size_t c = 0; c + 1 < n; ++c) ++pairs[{row[c], row[c + 1]}];
    EXPECT_EQ(pairs.size(), n * (n - 1));
    for (const auto& [pair, count] : pairs) EXPECT_EQ(count, 2);
  }
}

TEST(LatinSquare, RejectsSquaresThatAreNot) {
  EXPECT_FALSE(check_latin({{0, 1}, {1, 0}}, 3));             // wrong size
  EXPECT_FALSE(check_latin({{0, 1, 2}, {0, 2, 1}, {2, 1, 0}}, 3));  // column repeats
  EXPECT_FALSE(check_latin({{0, 0, 2}, {1, 2, 0}, {2, 1, 1}}, 3));  // row repeats
  EXPECT_FALSE(check_latin({{0, 1, 3}, {1, 2, 0}, {2, 0, 1}}, 3));  // out of range
  EXPECT_TRUE(check_latin({{0, 1, 2}, {1, 2, 0}, {2, 0, 1}}, 3));
}

TEST(LatinSquare, ParticipantsCycleThroughRows) {
  const Square sq = williams_design(4);
  EXPECT_EQ(row_for_participant(sq, 1), 0u);
  EXPECT_EQ(row_for_participant(sq, 4), 3u);
  EXPECT_EQ(row_for_participant(sq, 5), 0u);
  EXPECT_EQ(row_for_participant(sq, 10), 1u);
}

namespace {

StaircaseSpec spec(int up, int down, double start, std::vector<double> steps, int reversals,
                   int max_trials, int discard) {
  StaircaseSpec s;
  s.name = std::string(1, 's');  // not `= "s"`: GCC 12 warns falsely (-Wrestrict)
  s.start = start;
  s.up = up;
  s.down = down;
  s.step_sizes = std::move(steps);
  s.stop_reversals = reversals;
  s.max_trials = max_trials;
  s.discard_reversals = discard;
  s.min = -100.0;
  s.max = 100.0;
  return s;
}

// A simulated observer with a logistic psychometric function, answering
// "positive" with probability 1 / (1 + exp(−(x − mu)/scale)). Deterministic
// for a given seed.
double run_to_threshold(int up, int down, std::uint64_t seed, double mu, double scale) {
  Engine rng(seed);
  Staircase s(spec(up, down, mu + 3.0 * scale, {0.8 * scale, 0.4 * scale, 0.2 * scale}, 200, 100000, 20));
  while (!s.finished()) {
    const double p = 1.0 / (1.0 + std::exp(-(s.value() - mu) / scale));
    s.respond(uniform01(rng) < p);
  }
  return *s.threshold();
}

// The level where P(positive) = target.
double quantile(double target, double mu, double scale) {
  return mu + scale * std::log(target / (1.0 - target));
}

double mean_threshold(int up, int down, double mu, double scale) {
  double sum = 0.0;
  const int runs = 20;
  for (int r = 0; r < runs; ++r) sum += run_to_threshold(up, down, 1000 + static_cast<std::uint64_t>(r), mu, scale);
  return sum / runs;
}

}  // namespace

TEST(Staircase, OneUpTwoDownConvergesOnSeventyPointSevenPercent) {
  const double mu = 0.01, scale = 0.005;
  const double want = quantile(std::sqrt(0.5), mu, scale);  // p² = ½ → 70.7 %
  const double got = mean_threshold(1, 2, mu, scale);
  EXPECT_NEAR(got, want, 0.15 * scale);
  // And clearly not the 50 % point.
  EXPECT_GT(got - mu, 0.6 * scale);
}

TEST(Staircase, OneUpOneDownFindsThePointOfSubjectiveEquality) {
  const double mu = -0.02, scale = 0.004;
  EXPECT_NEAR(mean_threshold(1, 1, mu, scale), mu, 0.15 * scale);
}

TEST(Staircase, OneUpThreeDownConvergesOnSeventyNinePointFourPercent) {
  const double mu = 0.0, scale = 1.0;
  EXPECT_NEAR(mean_threshold(1, 3, mu, scale), quantile(std::cbrt(0.5), mu, scale), 0.15 * scale);
}

TEST(Staircase, StepScheduleAdvancesAtReversalsAndCountsThem) {
  Staircase s(spec(1, 2, 10.0, {4.0, 2.0, 1.0}, 3, 100, 0));
  s.respond(true);
  EXPECT_EQ(s.value(), 10.0);  // one positive: no move yet (2-down)
  s.respond(true);
  EXPECT_EQ(s.value(), 6.0);  // down by the first step
  s.respond(false);
  // 1-up fires and the direction changes: a reversal at 6, after which the
  // second step size applies to this very move.
  EXPECT_EQ(s.reversals(), 1);
  EXPECT_EQ(s.current_step(), 2.0);
  EXPECT_EQ(s.value(), 8.0);
  s.respond(true);
  s.respond(true);
  EXPECT_EQ(s.reversals(), 2);
  EXPECT_EQ(s.current_step(), 1.0);
  EXPECT_EQ(s.value(), 7.0);
  s.respond(false);
  EXPECT_EQ(s.value(), 8.0);
  EXPECT_EQ(s.reversals(), 3);
  EXPECT_EQ(s.current_step(), 1.0);  // the last step size repeats
  EXPECT_TRUE(s.finished());
  EXPECT_EQ(s.reversal_values(), (std::vector<double>{6.0, 8.0, 7.0}));
  EXPECT_DOUBLE_EQ(*s.threshold(), 7.0);
}

TEST(Staircase, StopsAtMaxTrialsAndClampsToItsRange) {
  StaircaseSpec sp = spec(1, 1, 0.0, {1.0}, 50, 5, 0);
  sp.min = -2.0;
  sp.max = 2.0;
  Staircase s(sp);
  for (int i = 0; i < 5; ++i) s.respond(true);
  EXPECT_EQ(s.value(), -2.0);
  EXPECT_TRUE(s.finished());
  EXPECT_EQ(s.threshold(), std::nullopt);  // never reversed
}

TEST(Staircase, InterleavedSetOnlyServesOpenStaircases) {
  InterleavedStaircases set({spec(1, 1, 0.0, {1.0}, 100, 3, 0), spec(1, 1, 0.0, {1.0}, 100, 10, 0)});
  Engine rng(5);
  std::map<std::size_t, int> served;
  while (!set.finished()) {
    const std::size_t i = set.next(rng);
    ASSERT_FALSE(set.at(i).finished());
    set.at(i).respond(i == 0);
    ++served[i];
  }
  EXPECT_EQ(served[0], 3);
  EXPECT_EQ(served[1], 10);
}

TEST(Adjustment, StepsClampAndConfirmFreezes) {
  AdjustmentSpec a;
  a.min = -0.1;
  a.max = 0.1;
  a.step = 0.02;
  a.fine_step = 0.005;
  Adjustment adj(a, 0.05);
  adj.increase();
  EXPECT_NEAR(adj.value(), 0.07, 1e-15);
  adj.increase();
  adj.increase();
  EXPECT_EQ(adj.value(), 0.1);
  adj.decrease(true);
  EXPECT_NEAR(adj.value(), 0.095, 1e-15);
  EXPECT_EQ(adj.steps(), 4);
  adj.confirm();
  adj.decrease();
  EXPECT_NEAR(adj.value(), 0.095, 1e-15);
  EXPECT_TRUE(adj.confirmed());
  EXPECT_EQ(Adjustment(a, 5.0).value(), 0.1);  // a start outside the range is clamped
}
