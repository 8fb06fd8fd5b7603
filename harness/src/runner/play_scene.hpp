// What a play block draws (docs/billiards.md): the table and its balls,
// placed from the physics at a time, as the session showed them and as
// `replay` draws them again from the stored shots.
#pragma once

#include "curvlab/harness/billiards/shot.hpp"
#include "curvlab/harness/data/records.hpp"
#include "curvlab/harness/runner/stimulus_kind.hpp"

#include <vector>

namespace curvlab::harness::runner {

namespace phys = curvlab::geometry::billiards;

class PlayScene {
 public:
  // Adds the table and one ball per entry of `balls` to the scene.
  PlayScene(renderer::Scene& scene, const World& world, const phys::Parameters& params, std::size_t balls);
  // The balls of `system` at time t_s (≥ its time): pose, spin, and hidden
  // once pocketed. Edits only what changed, so a still frame stays still.
  void show(renderer::Scene& scene, const phys::System& system, double t_s) const;
  void hide(renderer::Scene& scene) const;

 private:
  geometry::Space space_;
  double radius_m_ = 0.0;
  std::vector<std::size_t> balls_;
  std::size_t table_ = 0;
};

// The balls of a play block at display time t_ns, from its stored shots: the
// rest state before or after a shot, or, during one, the shot simulated
// again from its stored inputs. Empty when the block stored no shot yet.
struct PlayState {
  phys::Cloth cloth;
  phys::Parameters params;
  std::vector<billiards::BallPlace> balls;
  std::optional<phys::System> system;  // at rest or rolling
  double t_s = 0.0;                    // the time to show the system at
};
Result<PlayState> play_state_at(const World& world, const std::vector<data::ShotRecord>& shots, std::int64_t t_ns);

}  // namespace curvlab::harness::runner
