// The stimulus kinds (runner/stimulus_kind.hpp) and the one scene builder
// (runner/stimulus.hpp): which kind a trial judges, which objects its scene
// holds and shows per phase, the protocol's dimensions in every caller's
// scene, a standing stimulus that leaves unchanged frames unchanged, and the
// settings each kind's records store.
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/protocol/settings_json.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace rn = curvlab::harness::runner;
namespace protocol = curvlab::harness::protocol;
using curvlab::geometry::SpaceKind;

namespace {

protocol::Settings settings(bool stick, bool table, std::int64_t balls = 0) {
  protocol::Settings s;
  s.space.kind = SpaceKind::H3;
  s.stimulus.show_stick = stick;
  s.stimulus.show_table = table;
  s.stimulus.balls = balls;
  return s;
}

rn::TrialScene trial_scene(const protocol::Settings& s) {
  auto world = rn::make_world(s);
  EXPECT_TRUE(world);
  auto built = rn::TrialScene::build(world.value(), s, "prompt", CURVLAB_DEFAULT_FONT);
  EXPECT_TRUE(built) << (built ? std::string() : built.error().message);
  return std::move(built).value();
}

// The names of the visible objects.
std::vector<std::string> visible(const curvlab::renderer::Scene& scene) {
  std::vector<std::string> names;
  for (const auto& o : scene.objects())
    if (o.visible) names.push_back(o.name);
  return names;
}

}  // namespace

TEST(StimulusKinds, TheStickIsJudgedWhenShownAndTheTableOtherwise) {
  EXPECT_EQ(rn::judged_kind(settings(true, true)).name(), "stick");
  EXPECT_EQ(rn::judged_kind(settings(true, false)).name(), "stick");
  EXPECT_EQ(rn::judged_kind(settings(false, true)).name(), "table");
  EXPECT_EQ(rn::judged_kind(settings(false, false)).name(), "table");
  // The stick's three points (ends and middle), the fixated one its middle;
  // the H3 pentagon's five edge midpoints and its centre, fixated.
  const auto s = settings(true, true);
  const auto world = rn::make_world(s).value();
  const auto placement = rn::place_stimulus(world, s, curvlab::geometry::Isometry::identity());
  EXPECT_EQ(rn::judged_points(world, s, placement).size(), 3u);
  EXPECT_EQ(rn::judged_kind(s).fixated_point(3), 1u);
  const auto t = settings(false, true);
  EXPECT_EQ(rn::judged_points(world, t, placement).size(), 6u);
  EXPECT_EQ(rn::judged_kind(t).fixated_point(6), 5u);
}

TEST(StimulusKinds, TheSceneHoldsTheShownKindsAndShowsThemPerPhase) {
  auto stick_only = trial_scene(settings(true, false));
  EXPECT_EQ(stick_only.scene().objects().size(), 4u);  // the stick, prompt, fixation, page
  auto all = trial_scene(settings(true, true, 3));
  EXPECT_EQ(all.scene().objects().size(), 8u);  // and the table and three balls
  EXPECT_TRUE(visible(all.scene()).empty());    // built hidden
  all.show(rn::Phase::fixation, true);
  EXPECT_EQ(visible(all.scene()), std::vector<std::string>{"fixation"});
  all.show(rn::Phase::stimulus, true);
  auto shown = visible(all.scene());
  std::sort(shown.begin(), shown.end());
  EXPECT_EQ(shown, (std::vector<std::string>{"ball", "ball", "ball", "cue stick", "table"}));
  all.show(rn::Phase::response, false);
  EXPECT_EQ(visible(all.scene()), std::vector<std::string>{"prompt"});
}

TEST(StimulusKinds, AStandingStimulusLeavesAnUnchangedFrameUnchanged) {
  // Today's kinds stand still: a frame's update changes nothing, so the
  // headless renderer may still skip an unchanged frame (scene.hpp).
  auto t = trial_scene(settings(true, true, 2));
  t.show(rn::Phase::stimulus, true);
  const auto before = t.scene().revision();
  rn::FramePoses poses;
  poses.pose[0] = curvlab::geometry::translation_m(curvlab::geometry::Space{SpaceKind::H3, 1.0},
                                                   curvlab::geometry::Vec3(0.1, 0.0, 0.0));
  t.update(1'000'000'000, poses);
  EXPECT_EQ(t.scene().revision(), before);
}

TEST(StimulusKinds, EveryCallerDrawsTheProtocolsDimensions) {
  // One set of dimensions: the protocol's stick (12 mm radius) and balls
  // (57.15 mm), whether a session or `curvlab render` builds the scene.
  const protocol::Settings defaults;
  auto s = rn::viewed_scene(rn::SceneKind::billiards, defaults, {}, "prompt", CURVLAB_DEFAULT_FONT);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(s.value().placement.stick.radius_m, defaults.stimulus.stick_radius_m);
  EXPECT_EQ(s.value().placement.stick.radius_m, 0.012);
  int balls = 0;
  for (const auto& o : s.value().scene.objects())
    if (o.name == "ball") {
      ++balls;
      ASSERT_EQ(o.info.bounds.size(), 1u);
      EXPECT_EQ(o.info.bounds[0].radius_m, 0.028575);
    }
  EXPECT_EQ(balls, 3);
}

TEST(StimulusKinds, EachKindsRecordSettingsAreInTheStoredStimulusRecord) {
  const protocol::Settings s;
  const auto record = protocol::settings_json(s, protocol::derive(s).value(), protocol::SettingsRecord::stimulus);
  for (const rn::StimulusKind* kind : rn::stimulus_kinds())
    for (const std::string_view path : kind->record_settings())
      EXPECT_TRUE(record.contains(protocol::stimulus_key(path))) << kind->name() << ": " << path;
}
