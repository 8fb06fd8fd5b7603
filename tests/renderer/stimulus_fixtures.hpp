// The renderer tests' stimuli: a scene of a space as the session runner
// builds it (runner/stimulus.hpp, viewed_scene: protocol settings, the
// response window's stimulus and prompt), and the frame that views it with a
// 90° square field of view and a 63 mm IPD.
#pragma once

#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/scene.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <string>

namespace curvlab::renderer::fixtures {

using harness::runner::SceneKind;
using StimulusScene = harness::runner::ViewedScene;

inline const char* const kPrompt = "Is the cue stick bent toward you,\nstraight, or bent away?";

// The protocol's default settings in a space, with a stick bent by sagitta_m.
inline harness::protocol::Settings settings_in(geometry::SpaceKind kind, double sagitta_m = 0.0) {
  harness::protocol::Settings s;
  s.space.kind = kind;
  s.stimulus.stick_sagitta_m = sagitta_m;
  return s;
}

inline StimulusScene make_from(SceneKind scene, const harness::protocol::Settings& s, double yaw_rad = 0.0) {
  auto made = harness::runner::viewed_scene(scene, s, {.yaw_rad = yaw_rad}, kPrompt, CURVLAB_DEFAULT_FONT);
  EXPECT_TRUE(made) << (made ? std::string() : made.error().message);
  return std::move(made).value();
}

inline StimulusScene make(geometry::SpaceKind kind, SceneKind scene, double yaw_rad = 0.0) {
  return make_from(scene, settings_in(kind), yaw_rad);
}

inline FrameDescription frame_for(const StimulusScene& s, ViewPreset preset, std::uint32_t px = 1024) {
  FrameDescription f;
  f.space = s.space;
  f.settings = ViewSettings::preset(preset);
  f.head = s.head;
  f.rig = StereoRig::from_ipd(0.063, Fov::symmetric(std::numbers::pi / 2.0, 1.0));
  f.width_px = px;
  f.height_px = px;
  return f;
}

}  // namespace curvlab::renderer::fixtures
