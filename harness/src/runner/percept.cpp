#include "curvlab/harness/runner/percept.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <numbers>

namespace curvlab::harness::runner {
namespace {

constexpr double kArcmin = std::numbers::pi / (180.0 * 60.0);
constexpr double kArcsec = kArcmin / 60.0;

}  // namespace

Percept without_disparity(const ObserverParams& observer) {
  Percept p;
  p.noise_sd_m = 1.0 / observer.slope_per_m;
  p.disparity = false;
  return p;
}

Percept human_percept(const geometry::HumanPercept& hp, double sagitta_m, const ObserverParams& observer) {
  HumanAccount a;
  a.threshold_arcsec = hp.threshold_rad / kArcsec;
  a.signal_arcsec = sagitta_m / hp.depth_per_disparity_m / kArcsec;
  a.d_prime = a.signal_arcsec / a.threshold_arcsec;
  a.perceived_distance_m = hp.fixation.perceived_distance_m;
  a.vergence_demand_arcmin = hp.fixation.demand_rad / kArcmin;
  a.pedestal_arcmin = hp.fixation.pedestal_rad / kArcmin;
  a.worst_fusion = hp.worst_fusion;
  a.fused = hp.fused;
  Percept p = hp.fused ? Percept{sagitta_m, hp.depth_per_disparity_m * hp.threshold_rad, true, std::nullopt}
                       : without_disparity(observer);
  p.human = a;
  return p;
}

Percept perceive(const World& world, const protocol::Settings& s, const Placement& placement,
                 const geometry::Isometry& head, const ObserverParams& observer) {
  Percept p;
  p.noise_sd_m = 1.0 / observer.slope_per_m;
  const geometry::ViewPreset preset = perceived_preset(s);
  switch (observer.model) {
    case ObserverModel::physical: p.sagitta_m = physical_sagitta_m(s); return p;
    case ObserverModel::random: return p;
    case ObserverModel::triangulation:
      if (!geometry::binocular(preset)) return without_disparity(observer);
      p.sagitta_m = perceived_sagitta_m(world, s, placement, head);
      return p;
    case ObserverModel::human:
    case ObserverModel::image: break;
  }
  if (!geometry::binocular(preset)) return without_disparity(observer);
  const auto eyes = geometry::eyes_from_ipd(s.viewing.ipd_m);
  const auto points = judged_points(world, s, placement);
  // The eyes fixate the stick's middle or the table's centre.
  const std::size_t fixated = judged_kind(s).fixated_point(points.size());
  const geometry::HumanPercept hp =
      geometry::perceive_human_at(world.space, head, eyes, preset, points, fixated, observer.vision);
  const double sagitta = perceived_sagitta_with(world, s, hp.points_m, [&](const geometry::Point& q) {
    return geometry::perceive_with(hp.fixation, eyes, geometry::sight_lines(world.space, head, eyes, preset, q));
  });
  return human_percept(hp, sagitta, observer);
}

std::string human_account_json(const HumanAccount& a) {
  nlohmann::ordered_json j;
  j["fused"] = a.fused;
  j["signal_arcsec"] = a.signal_arcsec;
  j["threshold_arcsec"] = a.threshold_arcsec;
  j["d_prime"] = a.d_prime;
  j["perceived_distance_m"] = a.perceived_distance_m;
  j["vergence_demand_arcmin"] = a.vergence_demand_arcmin;
  j["pedestal_arcmin"] = a.pedestal_arcmin;
  j["worst_fusion"] = a.worst_fusion;
  return j.dump();
}

}  // namespace curvlab::harness::runner
