// The image-reading simulated participant (`--observer image`, DESIGN.md §4
// "Stimulus fidelity"): at each onset it draws the trial's stereo pair
// offscreen with the trial's eye geometry — the stick as the participant
// sees it, with the same eyes, projection and pose, against the background
// (the table and panels left out, so that the stick stands out as a figure) —
// and reads the stick from the two images (harness/measure) with the human
// observer's limits: the rings' disparities, fixating the middle one, give
// the perceived sagitta, its noise and whether it fused. The usual response
// model (observer.hpp) turns that percept into an answer.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/runner/percept.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/renderer/context.hpp"
#include "curvlab/renderer/offscreen.hpp"
#include "curvlab/renderer/renderer.hpp"

#include <memory>
#include <optional>

namespace curvlab::harness::runner {

// What one onset shows the observer.
struct OnsetView {
  renderer::ViewSettings settings;
  geometry::Isometry head;  // the nose at onset
  renderer::StereoRig rig;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
};

// Owns its Vulkan context, renderer and offscreen target (one thread).
class OnsetReader {
 public:
  static Result<std::unique_ptr<OnsetReader>> create();
  // The stick's percept read from the onset pair by `observer`; nullopt
  // when the trial judges the table (the images are read for the stick only).
  Result<std::optional<Percept>> read(const World& world, const protocol::Settings& s, const Placement& placement,
                                      const OnsetView& view, const ObserverParams& observer);

 private:
  explicit OnsetReader(renderer::Context ctx);
  renderer::Context ctx_;
  renderer::Renderer renderer_;
  std::optional<renderer::OffscreenTarget> target_;
};

// Writes what `curvlab measure stick` needs next to a trial's onset images
// (`run --images`): the eyes and the stick (measure/stick.hpp, scene_json).
// Trials that show no stick write nothing.
Result<Done> write_onset_record(const std::string& path, const World& world, const protocol::Settings& s,
                                const Placement& placement, const OnsetView& view);

// Done when every stick trial of the protocol has a marked stick (a plain
// stick gives the images nothing to match along its length); otherwise
// which block and what to set.
Result<Done> check_image_observer(const protocol::Protocol& p);

}  // namespace curvlab::harness::runner
