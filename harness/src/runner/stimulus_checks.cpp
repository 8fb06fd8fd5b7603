#include "curvlab/harness/runner/stimulus_checks.hpp"

#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/runner/percept.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include "curvlab/geometry/perception.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <optional>
#include <set>

namespace curvlab::harness::runner {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

std::string label_of(const std::vector<std::pair<std::string, std::string>>& levels) {
  std::string label;
  for (const auto& [f, l] : levels) label += (label.empty() ? "" : " ") + f + "=" + l;
  return label.empty() ? "(no factors)" : label;
}

std::string where_of(const std::string& block, const std::string& condition) {
  return "block " + block + ", condition " + condition;
}

// The judged points' names, in judged_points' order.
std::string point_name(const std::string& judged, std::size_t i, std::size_t n) {
  if (judged == "stick") return i == 0 ? "left end" : i + 1 == n ? "right end" : "middle";
  if (i + 1 == n) return "centre";
  return "edge midpoint " + std::to_string(i + 1);
}

std::string degrees(double rad) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f°", rad * kDeg);
  return buf;
}

// The human model's perceived sagitta of the condition's shape made
// physically straight and placed in E3, and its noise SD there: its own
// frontal-plane distortion (nullopt when E3 cannot hold the settings).
std::optional<std::pair<double, double>> frontal_plane_distortion(const protocol::Settings& condition) {
  protocol::Settings e = condition;
  e.space.kind = geometry::SpaceKind::E3;
  e.stimulus.stick_sagitta_m = 0.0;
  e.stimulus.table_sagitta_m = 0.0;
  auto world = make_world(e);
  if (!world) return std::nullopt;
  const geometry::Isometry head = standing_head(*world, e);
  const Percept p = perceive(*world, e, place_stimulus(*world, e, head), head, ObserverParams{});
  if (!p.disparity) return std::nullopt;
  return std::pair{p.sagitta_m, p.noise_sd_m};
}

}  // namespace

std::string_view to_string(StimulusWarningKind kind) {
  switch (kind) {
    case StimulusWarningKind::out_of_view: return "out_of_view";
    case StimulusWarningKind::model_range: return "model_range";
    case StimulusWarningKind::no_convergence: return "no_convergence";
  }
  return "unknown";
}

std::vector<FieldOfView> fields_of_view(const protocol::Protocol& p) {
  const double half = std::numbers::pi / 4.0;
  std::vector<FieldOfView> out{{"a headset's default 90°×90° field of view", half, half}};
  const double aspect = double(p.resolution_height) / double(p.resolution_width);
  const double half_v = std::atan(std::tan(half) * aspect);
  if (std::abs(half_v - half) > 1e-9)
    out.push_back({"the protocol's field of view (90° wide at " + std::to_string(p.resolution_width) + "×" +
                       std::to_string(p.resolution_height) + ", as headless runs and preview draw it)",
                   half, half_v});
  return out;
}

namespace {

// One condition seen from where the headless participant stands: for each
// shown eye, the judged points a field of view loses (and the first field
// that loses them), and the judged point farthest from the fixated one.
struct ViewCheck {
  std::string lost;  // "" when every judged point stays in view
  double worst_rad = 0.0;
  std::string worst_point;
};

ViewCheck check_view(const World& world, const protocol::Settings& s, const std::vector<geometry::Point>& points,
                     const std::string& judged, const std::vector<FieldOfView>& fovs) {
  const geometry::Isometry head = standing_head(world, s);
  const geometry::ViewPreset preset = perceived_preset(s);
  const auto eyes = geometry::eyes_from_ipd(s.viewing.ipd_m);
  const bool shown[2] = {s.viewing.eyes != renderer::EyeSelection::right,
                         s.viewing.eyes != renderer::EyeSelection::left};
  const std::size_t fixated = judged_kind(s).fixated_point(points.size());
  const auto to_fixated = geometry::sight_lines(world.space, head, eyes, preset, points[fixated]);
  ViewCheck out;
  std::string lost_by[2];
  std::string fov_named;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto lines = geometry::sight_lines(world.space, head, eyes, preset, points[i]);
    for (int e = 0; e < 2; ++e) {
      if (!shown[e]) continue;
      const geometry::Vec3 d = lines[e].direction;
      const double h = std::atan2(std::abs(d.x), -d.z);
      const double v = std::atan2(std::abs(d.y), -d.z);
      for (const auto& fov : fovs) {
        if (d.z < 0.0 && h <= fov.half_horizontal_rad && v <= fov.half_vertical_rad) continue;
        lost_by[e] += std::string(lost_by[e].empty() ? "" : ", ") + point_name(judged, i, points.size()) + " (" +
                      degrees(h) + " across, " + degrees(v) + " vertically)";
        if (fov_named.find(fov.name) == std::string::npos)
          fov_named += std::string(fov_named.empty() ? "" : " or ") + fov.name;
        break;
      }
      const double ecc = std::acos(std::clamp(glm::dot(d, to_fixated[e].direction), -1.0, 1.0));
      // Ties (a stick's two ends seen symmetrically) go to the first point
      // whatever the last bits of the build's arithmetic say.
      if (ecc > out.worst_rad + 1e-9) {
        out.worst_rad = ecc;
        out.worst_point = point_name(judged, i, points.size());
      }
    }
  }
  for (int e = 0; e < 2; ++e)
    if (!lost_by[e].empty())
      out.lost += std::string(out.lost.empty() ? "" : "; ") + "the " + (e == 0 ? "left" : "right") + " eye loses the " +
                  judged + "'s " + lost_by[e];
  if (!out.lost.empty()) out.lost += " — outside " + fov_named;
  return out;
}

// The human model's range, per block: its binocular conditions, those that
// reach beyond the eccentricity its data span where its own distortion
// exceeds its noise, and the worst of them.
struct ModelRange {
  int beyond = 0, conditions = 0;
  double worst_rad = 0.0;
  double distortion_m = 0.0, noise_sd_m = 0.0;  // the model's bias there, and its noise
  std::string point, judged;

  void add(const protocol::Settings& s, const ViewCheck& view, const std::string& judged_name) {
    ++conditions;
    if (view.worst_rad * kDeg <= kHumanModelEccentricityDeg) return;
    // Beyond the data, what the model predicts there matters when its own
    // frontal-plane distortion is larger than its noise: the bow it sees in
    // the same shape, physically straight, in Euclidean space, where an
    // ideal observer sees none.
    const auto distortion = frontal_plane_distortion(s);
    if (!distortion || std::abs(distortion->first) <= distortion->second) return;
    ++beyond;
    if (std::abs(distortion->first) <= std::abs(distortion_m)) return;
    worst_rad = view.worst_rad;
    point = view.worst_point;
    judged = judged_name;
    distortion_m = distortion->first;
    noise_sd_m = distortion->second;
  }

  [[nodiscard]] std::string text(const std::string& block) const {
    char mm[96];
    std::snprintf(mm, sizeof mm, "%+.0f mm against a noise SD of %.1f mm", distortion_m * 1000.0, noise_sd_m * 1000.0);
    return "block " + block + ": in " + std::to_string(beyond) + " of its " + std::to_string(conditions) +
           " binocular conditions the human observer model's predictions lie outside its range of validity: the "
           "judged points reach beyond the ±" +
           degrees(kHumanModelEccentricityDeg / kDeg) + " of eccentricity its data span (the " + judged + "'s " +
           point + " " + degrees(worst_rad) + " from the fixated point), where its own frontal-plane distortion "
           "reaches " + mm + " (a physically straight shape in E3); predicted values, PSEs and power there reflect "
           "the model, not the space";
  }
};

}  // namespace

std::vector<StimulusWarning> stimulus_warnings(const protocol::Protocol& p) {
  std::vector<StimulusWarning> out;
  const auto fovs = fields_of_view(p);
  const protocol::Design design = protocol::expand_design(p, 1);
  std::set<std::pair<std::string, std::string>> seen;
  std::vector<std::pair<std::string, ModelRange>> ranges;  // in design order
  for (const auto& t : design.trials) {
    const std::string condition = label_of(t.levels);
    if (!seen.insert({t.block, condition}).second) continue;
    auto world = make_world(t.settings);
    if (!world) continue;  // the validator reports an impossible table
    const auto& s = t.settings;
    const auto points = judged_points(*world, s, place_stimulus(*world, s, standing_head(*world, s)));
    if (points.empty()) continue;
    const std::string judged(judged_kind(s).name());
    const ViewCheck view = check_view(*world, s, points, judged, fovs);
    if (!view.lost.empty())
      out.push_back({StimulusWarningKind::out_of_view, t.block, condition,
                     where_of(t.block, condition) + ": the stimulus leaves the view: " + view.lost});
    if (!geometry::binocular(perceived_preset(s))) continue;
    auto it = std::find_if(ranges.begin(), ranges.end(), [&](const auto& r) { return r.first == t.block; });
    if (it == ranges.end()) it = ranges.insert(ranges.end(), {t.block, ModelRange{}});
    it->second.add(s, view, judged);
  }
  for (const auto& [block, r] : ranges)
    if (r.beyond > 0) out.push_back({StimulusWarningKind::model_range, block, "", r.text(block)});
  return out;
}

std::vector<StimulusWarning> protocol_warnings(const protocol::Protocol& p) {
  auto out = stimulus_warnings(p);
  for (auto& w : convergence_warnings(predict_convergence(p, ObserverParams{}))) out.push_back(std::move(w));
  return out;
}

std::vector<StimulusWarning> convergence_warnings(const std::vector<StaircasePrediction>& staircases) {
  std::vector<StimulusWarning> out;
  for (const auto& sp : staircases) {
    if (sp.target_value) continue;
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  ": staircase %s cannot converge inside its range [%g, %g] of %s: the mean observer answers %s "
                  "with P = %.2f at %g and %.2f at %g, never %.1f%%; the track would run into its limit",
                  sp.staircase.c_str(), sp.min, sp.max, sp.parameter.c_str(), sp.positive.c_str(), sp.p_at_min,
                  sp.min, sp.p_at_max, sp.max, 100.0 * sp.target_p);
    const std::string condition = label_of(sp.levels);
    out.push_back({StimulusWarningKind::no_convergence, sp.block, condition, where_of(sp.block, condition) + buf});
  }
  return out;
}

}  // namespace curvlab::harness::runner
