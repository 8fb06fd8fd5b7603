// What the simulated observer perceives of a trial's judged shape, per model
// (observer.hpp, docs/runner.md "The simulated observer"): the signed
// sagitta and the SD of its noise in metres, and for the human model the
// account behind them — the disparity the perceived bow amounts to, the
// stereo threshold, the perceived distance and whether the shape fused.
#pragma once

#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/harness/runner/observer.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <optional>
#include <string>

namespace curvlab::harness::runner {

// The human model's account of one percept.
struct HumanAccount {
  // The perceived bow over the depth that one radian of relative disparity
  // signals at the perceived distance: the disparity the judgement rests
  // on, and its ratio to the threshold (d′, bias aside).
  double signal_arcsec = 0.0;
  double threshold_arcsec = 0.0;
  double d_prime = 0.0;
  double perceived_distance_m = 0.0;
  double vergence_demand_arcmin = 0.0;  // what the fixated point asks of the eyes (negative: diverge)
  double pedestal_arcmin = 0.0;         // its part beyond the eyes' reach
  double worst_fusion = 0.0;            // largest disparity over its fusional limit (> 1: double)
  bool fused = true;
};

struct Percept {
  double sagitta_m = 0.0;   // signed: + toward the viewer (stick), bulging up (table)
  double noise_sd_m = 0.0;  // SD of the response model's noise
  // Whether the judgement rests on disparity: false for one eye, and for
  // the human model when the shape is seen double (it then answers from
  // monocular information: no bow, the observer's metric noise).
  bool disparity = true;
  std::optional<HumanAccount> human;
};

// The percept of the judged shape for a viewer whose nose is at `head`.
Percept perceive(const World& world, const protocol::Settings& s, const Placement& placement,
                 const geometry::Isometry& head, const ObserverParams& observer);

// No disparity to go on (one eye): no bow, the observer's metric noise.
Percept without_disparity(const ObserverParams& observer);

// The human model's percept from a geometry::HumanPercept and the sagitta of
// its points (shared by the model and the image observer).
Percept human_percept(const geometry::HumanPercept& p, double sagitta_m, const ObserverParams& observer);

// The account as the onset event stores it (codebook: events, onset).
std::string human_account_json(const HumanAccount& a);

}  // namespace curvlab::harness::runner
