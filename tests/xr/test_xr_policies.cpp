// The headset's policies as pure values, without a runtime: where curvlab's
// STAGE space lies after the runtime moves STAGE's origin (stage_anchor.hpp),
// which refresh rate it asks for (refresh_rate.hpp), and when a trigger is a
// press (controllers.hpp).
#include "curvlab/harness/xr/controllers.hpp"
#include "curvlab/harness/xr/refresh_rate.hpp"
#include "curvlab/harness/xr/stage_anchor.hpp"
#include "curvlab/harness/xr/views.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace curvlab::harness::xr;

constexpr double kTol = 1e-5;  // m; XrPosef holds floats

XrPosef pose(double x, double y, double z, double yaw_deg) {
  StagePose p;
  p.position_m = {x, y, z};
  p.orientation = glm::angleAxis(yaw_deg * std::numbers::pi / 180.0, glm::dvec3(0, 1, 0));
  return to_xr_pose(p);
}

// Where a point with coordinates `x` in a space lies in its reference space
// (a pose maps the space's coordinates into the reference's).
glm::dvec3 apply(const XrPosef& p, const glm::dvec3& x) {
  const StagePose l = to_stage_pose(p);
  return l.orientation * x + l.position_m;
}

glm::dvec3 apply_inverse(const XrPosef& p, const glm::dvec3& x) {
  const StagePose l = to_stage_pose(p);
  return glm::inverse(l.orientation) * (x - l.position_m);
}

void expect_near(const glm::dvec3& a, const glm::dvec3& b) {
  EXPECT_NEAR(a.x, b.x, kTol);
  EXPECT_NEAR(a.y, b.y, kTol);
  EXPECT_NEAR(a.z, b.z, kTol);
}

// The table's corner, in the lab frame (the STAGE before any move).
const glm::dvec3 kCorner{0.4, 0.75, -0.6};

TEST(StageAnchor, StartsAtTheRuntimesStage) {
  StageAnchor a;
  expect_near(apply(a.offset(), kCorner), kCorner);
  EXPECT_FALSE(a.pending());
  EXPECT_FALSE(a.due(1'000'000'000));
}

// The runtime says STAGE's new origin lies at P in the old STAGE: the room
// did not move, so a lab point has runtime coordinates P⁻¹ · x from then on;
// the offset space must give the same.
TEST(StageAnchor, AMoveWithAPoseKeepsTheLabFrame) {
  StageAnchor a;
  const XrPosef moved = pose(1.0, 0.0, 2.0, 90.0);
  const auto offset = a.offset_after(true, moved);
  ASSERT_TRUE(offset.has_value());
  expect_near(apply(*offset, kCorner), apply_inverse(moved, kCorner));
}

TEST(StageAnchor, AMoveWithoutAPoseCannotKeepTheLabFrame) {
  StageAnchor a;
  EXPECT_FALSE(a.offset_after(false, pose(1.0, 0.0, 2.0, 90.0)).has_value());
}

// The new space is used from the first frame displayed at or after the
// runtime's change time, not before.
TEST(StageAnchor, TheNewSpaceWaitsForTheChangeTime) {
  StageAnchor a;
  const auto offset = a.offset_after(true, pose(0.5, 0.0, 0.0, 0.0));
  ASSERT_TRUE(offset.has_value());
  a.schedule(*offset, 2'000);
  EXPECT_TRUE(a.pending());
  EXPECT_FALSE(a.due(1'999));
  expect_near(apply(a.offset(), kCorner), kCorner);
  EXPECT_TRUE(a.due(2'000));
  a.follow();
  EXPECT_FALSE(a.pending());
  EXPECT_FALSE(a.due(3'000));
  expect_near(apply(a.offset(), kCorner), kCorner - glm::dvec3(0.5, 0.0, 0.0));
}

// Two moves, the second announced while the first still waits for its change
// time: the second composes with the first, so after both the lab point has
// the runtime coordinates P2⁻¹ · P1⁻¹ · x.
TEST(StageAnchor, MovesCompose) {
  const XrPosef first = pose(1.0, 0.0, 2.0, 90.0);
  const XrPosef second = pose(-0.3, 0.0, 0.7, -30.0);
  const glm::dvec3 runtime = apply_inverse(second, apply_inverse(first, kCorner));

  StageAnchor waiting;
  waiting.schedule(*waiting.offset_after(true, first), 1'000);
  waiting.schedule(*waiting.offset_after(true, second), 2'000);
  ASSERT_TRUE(waiting.due(2'000));
  waiting.follow();
  expect_near(apply(waiting.offset(), kCorner), runtime);

  StageAnchor followed;
  followed.schedule(*followed.offset_after(true, first), 1'000);
  followed.follow();
  followed.schedule(*followed.offset_after(true, second), 2'000);
  followed.follow();
  expect_near(apply(followed.offset(), kCorner), runtime);
}

TEST(RefreshRatePolicy, WithoutAProtocolRateNothingIsAsked) {
  RefreshRatePolicy p(std::nullopt);
  p.display_runs_at(72.0);
  EXPECT_FALSE(p.should_request());
  EXPECT_FALSE(p.choose({72.0f, 90.0f}).has_value());
}

TEST(RefreshRatePolicy, AsksOnlyForADifferentRate) {
  RefreshRatePolicy p(90.0);
  EXPECT_DOUBLE_EQ(p.current_hz(), 90.0);  // the common rate until the display says
  EXPECT_FALSE(p.should_request());
  p.display_runs_at(89.9);
  EXPECT_FALSE(p.should_request());
  p.display_runs_at(72.0);
  EXPECT_TRUE(p.should_request());
}

TEST(RefreshRatePolicy, ChoosesTheOfferedRateNearest) {
  RefreshRatePolicy p(90.0);
  p.display_runs_at(72.0);
  const auto chosen = p.choose({72.0f, 80.0f, 90.01f, 120.0f});
  ASSERT_TRUE(chosen.has_value());
  EXPECT_FLOAT_EQ(*chosen, 90.01f);
  EXPECT_FALSE(p.choose({72.0f, 120.0f}).has_value());
  EXPECT_FALSE(p.choose({}).has_value());
}

TEST(RefreshRatePolicy, SaysWhatIsOfferedWhenTheRateIsNot) {
  RefreshRatePolicy p(90.0);
  p.display_runs_at(72.0);
  EXPECT_EQ(p.not_offered_message({60.0f, 72.0f, 120.0f}),
            "the headset does not offer the protocol's 90 Hz (it offers 60, 72, 120 Hz); frames run at its 72 Hz");
}

// The change event curvlab's own request brings is already recorded; a
// change the runtime makes itself is the runtime's, and the protocol's rate
// is asked for again.
TEST(RefreshRatePolicy, TellsItsOwnChangeFromTheRuntimes) {
  RefreshRatePolicy p(90.0);
  p.display_runs_at(72.0);
  p.requested(90.0f, 90.0);
  EXPECT_DOUBLE_EQ(p.current_hz(), 90.0);
  EXPECT_FALSE(p.should_request());
  EXPECT_TRUE(p.on_change(90.0f));
  EXPECT_DOUBLE_EQ(p.current_hz(), 90.0);

  EXPECT_FALSE(p.on_change(72.0f));
  EXPECT_DOUBLE_EQ(p.current_hz(), 72.0);
  EXPECT_TRUE(p.should_request());
}

// A request is answered once: a second change event to the same rate is the
// runtime's own (recorded again).
TEST(RefreshRatePolicy, ARequestIsAnsweredOnce) {
  RefreshRatePolicy p(90.0);
  p.display_runs_at(72.0);
  p.requested(90.0f, 90.0);
  EXPECT_TRUE(p.on_change(90.0f));
  EXPECT_FALSE(p.on_change(90.0f));
  EXPECT_FALSE(p.should_request());
}

TEST(RefreshRatePolicy, AChangeAwayFromTheRequestedRateIsTheRuntimes) {
  RefreshRatePolicy p(90.0);
  p.display_runs_at(72.0);
  p.requested(90.0f, 90.0);
  EXPECT_FALSE(p.on_change(120.0f));
  EXPECT_DOUBLE_EQ(p.current_hz(), 120.0);
  EXPECT_TRUE(p.should_request());
}

// A press above 0.75, a release below 0.25: a finger resting half-way does
// not chatter, and the first read after the action became active is a
// baseline, not an event.
TEST(TriggerHysteresis, PressesAndReleasesWithHysteresis) {
  TriggerHysteresis t;
  EXPECT_FALSE(t.update(0.5f, false).has_value());
  EXPECT_EQ(t.update(0.8f, false), std::optional<bool>(true));
  EXPECT_FALSE(t.update(0.5f, false).has_value());
  EXPECT_FALSE(t.update(0.3f, false).has_value());
  EXPECT_EQ(t.update(0.2f, false), std::optional<bool>(false));
  EXPECT_FALSE(t.update(0.7f, false).has_value());
}

TEST(TriggerHysteresis, ABaselineReadIsNoEvent) {
  TriggerHysteresis t;
  EXPECT_FALSE(t.update(0.9f, true).has_value());
  EXPECT_TRUE(t.down());
  EXPECT_FALSE(t.update(0.9f, false).has_value());  // held across the baseline: no new press
  EXPECT_EQ(t.update(0.1f, false), std::optional<bool>(false));
  EXPECT_FALSE(t.update(0.1f, true).has_value());
  EXPECT_FALSE(t.down());
}

}  // namespace
