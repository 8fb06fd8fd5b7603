// The benchmarks' scenes: a trial's, as the session runner builds it
// (runner/stimulus.hpp, viewed_scene) from the protocol's default settings
// in a space, so a benchmark times and measures what participants see.
#pragma once

#include "curvlab/harness/runner/stimulus.hpp"

#include <cstdio>
#include <cstdlib>
#include <utility>

namespace bench {

using StimulusScene = curvlab::harness::runner::ViewedScene;
using curvlab::harness::runner::SceneKind;

// The scene; a scene that cannot be built ends the benchmark.
inline StimulusScene scene_of(curvlab::geometry::SpaceKind kind, SceneKind scene, double stick_sagitta_m = 0.0) {
  curvlab::harness::protocol::Settings s;
  s.space.kind = kind;
  s.stimulus.stick_sagitta_m = stick_sagitta_m;
  auto made = curvlab::harness::runner::viewed_scene(
      scene, s, {}, "Is the cue stick bent toward you,\nstraight, or bent away?", CURVLAB_DEFAULT_FONT);
  if (!made) {
    std::fprintf(stderr, "scene: %s\n", made.error().message.c_str());
    std::exit(1);
  }
  return std::move(made).value();
}

}  // namespace bench
