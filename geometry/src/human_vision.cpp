#include "curvlab/geometry/human_vision.hpp"

#include "curvlab/geometry/maps.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace curvlab::geometry {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
constexpr double kArcmin = kDegree / 60.0;
constexpr double kArcsec = kArcmin / 60.0;
// The nearest dioptric distance a contraction may produce stays above this
// (50 m), so that a perceived distance is always finite.
constexpr double kFarthestDioptres = 0.02;

// The eyes' axis (left → right), forward direction (orthogonal to it, in
// the plane containing −z) and up (axis × forward), as perception.cpp reads
// yaw.
struct Axes {
  Vec3 axis{1.0, 0.0, 0.0};
  Vec3 forward{0.0, 0.0, -1.0};
  Vec3 up{0.0, 1.0, 0.0};
};

Axes axes_of(const EyeOffsets& eyes) {
  Axes a;
  const Vec3 d = eyes.right_m - eyes.left_m;
  if (glm::length(d) > 0.0) a.axis = glm::normalize(d);
  const Vec3 minus_z(0.0, 0.0, -1.0);
  const Vec3 f = minus_z - glm::dot(minus_z, a.axis) * a.axis;
  if (glm::length(f) > 0.0) a.forward = glm::normalize(f);
  a.up = glm::cross(a.axis, a.forward);
  return a;
}

double yaw(const Axes& a, const Vec3& dir) { return std::atan2(glm::dot(dir, a.axis), glm::dot(dir, a.forward)); }

// Rodrigues' rotation of v by `angle` about the unit axis k. A positive
// angle about `up` lowers the yaw by that angle.
Vec3 rotated(const Vec3& v, const Vec3& k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  return v * c + glm::cross(k, v) * s + k * (glm::dot(k, v) * (1.0 - c));
}

Vec3 cyclopean(const std::array<SightLine, 2>& lines) {
  const Vec3 sum = lines[0].direction + lines[1].direction;
  return glm::length(sum) > 0.0 ? glm::normalize(sum) : Vec3(0.0, 0.0, -1.0);
}

double ipd_of(const EyeOffsets& eyes) { return glm::length(eyes.right_m - eyes.left_m); }

}  // namespace

double vergence_of(const EyeOffsets& eyes, const std::array<SightLine, 2>& lines) {
  const Axes a = axes_of(eyes);
  return yaw(a, lines[0].direction) - yaw(a, lines[1].direction);
}

double beyond_reach_rad(const HumanVision& v, double demand_rad) {
  return demand_rad - std::clamp(demand_rad, -v.divergence_limit_deg * kDegree, v.convergence_limit_deg * kDegree);
}

Fixation fixate(const HumanVision& v, double demand_rad, double ipd_m) {
  Fixation f;
  f.demand_rad = demand_rad;
  f.pedestal_rad = beyond_reach_rad(v, demand_rad);
  f.achieved_rad = demand_rad - f.pedestal_rad;
  // Dioptres signalled by the achieved vergence (negative when diverging),
  // pulled toward the specific distance's.
  const double signalled = 2.0 * std::tan(0.5 * f.achieved_rad) / ipd_m;
  const double dioptres = std::max(
      kFarthestDioptres, v.vergence_weight * signalled + (1.0 - v.vergence_weight) / v.specific_distance_m);
  f.perceived_distance_m = 1.0 / dioptres;
  f.perceived_rad = 2.0 * std::atan(0.5 * ipd_m * dioptres);
  return f;
}

Vec3 perceive_with(const Fixation& f, const EyeOffsets& eyes, const std::array<SightLine, 2>& lines) {
  const Axes a = axes_of(eyes);
  const double offset = f.perceived_rad - f.achieved_rad;  // added to every point's vergence
  const SightLine left{lines[0].origin_m, rotated(lines[0].direction, a.up, -0.5 * offset)};
  const SightLine right{lines[1].origin_m, rotated(lines[1].direction, a.up, 0.5 * offset)};
  const LineMeeting m = closest_approach(left, right);
  if (!m.parallel) return m.point;
  return m.point + 1e9 * cyclopean(lines);
}

double stereo_threshold_rad(const HumanVision& v, double pedestal_rad) {
  return v.threshold_arcsec * kArcsec + v.pedestal_fraction * std::abs(pedestal_rad);
}

double depth_per_disparity_m(const Fixation& f, double ipd_m) {
  const double s = std::sin(0.5 * f.perceived_rad);
  return 0.25 * ipd_m / (s * s);
}

HumanPercept perceive_human(const HumanVision& v, const EyeOffsets& eyes,
                            const std::vector<std::array<SightLine, 2>>& lines, std::size_t fixated) {
  HumanPercept p;
  if (lines.empty()) return p;
  fixated = std::min(fixated, lines.size() - 1);
  const double ipd = ipd_of(eyes);
  p.fixation = fixate(v, vergence_of(eyes, lines[fixated]), ipd);
  for (const auto& pair : lines) {
    p.points_m.push_back(perceive_with(p.fixation, eyes, pair));
    const double missed = std::abs(beyond_reach_rad(v, vergence_of(eyes, pair)));
    p.worst_fusion = std::max(p.worst_fusion, missed / (v.fusion_arcmin * kArcmin));
  }
  p.fused = p.worst_fusion <= 1.0;
  p.threshold_rad = stereo_threshold_rad(v, p.fixation.pedestal_rad);
  p.depth_per_disparity_m = depth_per_disparity_m(p.fixation, ipd);
  return p;
}

HumanPercept perceive_human_at(const Space& space, const Isometry& nose, const EyeOffsets& eyes, ViewPreset preset,
                               const std::vector<Point>& points, std::size_t fixated, const HumanVision& v) {
  std::vector<std::array<SightLine, 2>> lines;
  for (const Point& q : points) lines.push_back(sight_lines(space, nose, eyes, preset, q));
  return perceive_human(v, eyes, lines, fixated);
}

HumanStickPerception perceive_stick_human(const Space& space, const BentStick& stick, double distance_m,
                                          const EyeOffsets& eyes, ViewPreset preset, const HumanVision& v) {
  HumanStickPerception out;
  if (!binocular(preset)) return out;
  const Isometry frame = stick_frame(space, distance_m);
  std::vector<Point> points;
  const double half = stick.length_m / 2.0;
  for (const double u : {-half, 0.0, half}) points.push_back(stick.centre_point(space, frame, u));
  out.percept = perceive_human_at(space, Isometry::identity(), eyes, preset, points, 1, v);
  const auto& p = out.percept.points_m;
  out.perceived_sagitta_m = bow_toward_viewer(p[0], p[1], p[2]);
  return out;
}

}  // namespace curvlab::geometry
