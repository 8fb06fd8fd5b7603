// The renderer tests' stimuli: a stimulus scene of a space, and the frame
// that views it with a 90° square field of view and a 63 mm IPD.
#pragma once

#include "curvlab/renderer/plan.hpp"
#include "curvlab/renderer/scene.hpp"

#include <gtest/gtest.h>

#include <numbers>
#include <variant>

namespace curvlab::renderer::fixtures {

inline StimulusScene make(geometry::SpaceKind kind, SceneKind scene, double yaw_rad = 0.0) {
  StimulusOptions o;
  o.yaw_rad = yaw_rad;
  auto made = make_stimulus_scene(kind, scene, o);
  EXPECT_TRUE(std::holds_alternative<StimulusScene>(made));
  return std::get<StimulusScene>(std::move(made));
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
