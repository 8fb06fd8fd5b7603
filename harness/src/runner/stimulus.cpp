#include "curvlab/harness/runner/stimulus.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/harness/lab_volume.hpp"
#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/render_result.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/utf8.hpp"
#include "curvlab/renderer/mesh.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <numbers>

namespace curvlab::harness::runner {

using geometry::Isometry;
using geometry::Point;
using geometry::Vec3;
using protocol::Settings;

bool World::same_as(const World& other) const {
  return space.kind == other.space.kind && space.radius_m == other.space.radius_m &&
         table.sides == other.table.sides && table.side_rad == other.table.side_rad;
}

Result<World> make_world(const Settings& s) {
  auto shape = protocol::table_shape(s);
  if (!shape) return shape.error();
  const auto& t = shape.value();
  return World{geometry::Space{s.space.kind, t.radius_m}, t};
}

geometry::PhysicalTableFit nominal_calibration(const Settings& s) {
  geometry::PhysicalTableFit fit;
  fit.edge_m = s.table.edge_m;
  fit.height_m = s.table.height_m;
  return fit;
}

geometry::PhysicalTable physical_table(const Settings& s,
                                       const std::optional<geometry::PhysicalTableFit>& calibration) {
  const auto fit = calibration.value_or(nominal_calibration(s));
  geometry::PhysicalTable t;
  t.centre_x_m = fit.centre_m.x;
  t.centre_z_m = fit.centre_m.y;
  t.yaw_rad = fit.yaw_rad;
  t.edge_m = fit.edge_m;
  t.height_m = fit.height_m;
  return t;
}

std::string calibration_json(const geometry::PhysicalTableFit& fit) {
  nlohmann::ordered_json j;
  j["centre_x_m"] = fit.centre_m.x;
  j["centre_z_m"] = fit.centre_m.y;
  j["yaw_rad"] = fit.yaw_rad;
  j["edge_m"] = fit.edge_m;
  j["height_m"] = fit.height_m;
  j["rms_residual_m"] = fit.rms_residual_m;
  j["max_residual_m"] = fit.max_residual_m;
  j["corners_used"] = fit.corners_used;
  // Each touch's distance from its fitted corner, in touch order (none for a
  // table that was not touched: the nominal one).
  auto residuals = nlohmann::ordered_json::array();
  for (int c = 0; c < std::clamp(fit.corners_used, 0, 4); ++c)
    residuals.push_back(fit.corner_residual_m[static_cast<std::size_t>(c)]);
  j["residuals_m"] = residuals;
  return j.dump();
}

namespace {

// The 1-based line of the byte at `at`.
std::size_t line_at(const std::string& text, std::size_t at) {
  return 1 + static_cast<std::size_t>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

// The 1-based line of the first `"key"` in a JSON text, 0 when absent: the
// line a message about that member names.
std::size_t line_of_key(const std::string& text, const std::string& key) {
  const auto at = text.find('"' + key + '"');
  return at == std::string::npos ? 0 : line_at(text, at);
}

// A member's allowed range (inclusive unless `open`) and how a message says it.
struct CalibrationRange {
  const char* key;
  double lo;
  double hi;
  bool open;
  const char* expected;
};

constexpr CalibrationRange kCalibrationRanges[] = {
    {"centre_x_m", -kLabBound_m, kLabBound_m, false, "metres within ±100 (the lab volume)"},
    {"centre_z_m", -kLabBound_m, kLabBound_m, false, "metres within ±100 (the lab volume)"},
    {"yaw_rad", -2.0 * std::numbers::pi, 2.0 * std::numbers::pi, false, "radians within ±2π"},
    {"edge_m", 0.2, 5.0, true, "metres in (0.2, 5)"},
    {"height_m", 0.3, 1.5, true, "metres in (0.3, 1.5)"},
    {"rms_residual_m", 0.0, kLabBound_m, false, "metres in [0, 100]"},
    {"max_residual_m", 0.0, kLabBound_m, false, "metres in [0, 100]"},
    {"residuals_m", 0.0, kLabBound_m, false, "metres in [0, 100]"},
};

bool in_range(const CalibrationRange& r, double v) {
  return std::isfinite(v) && (r.open ? v > r.lo && v < r.hi : v >= r.lo && v <= r.hi);
}

// The first member of the calibration outside its range, as a message.
std::optional<std::string> calibration_out_of_range(const geometry::PhysicalTableFit& fit) {
  const double values[] = {fit.centre_m.x, fit.centre_m.y, fit.yaw_rad, fit.edge_m, fit.height_m,
                           fit.rms_residual_m, fit.max_residual_m};
  for (std::size_t k = 0; k < std::size(values); ++k)
    if (!in_range(kCalibrationRanges[k], values[k])) return std::string(kCalibrationRanges[k].key);
  for (int c = 0; c < std::clamp(fit.corners_used, 0, 4); ++c)
    if (!in_range(kCalibrationRanges[std::size(values)], fit.corner_residual_m[static_cast<std::size_t>(c)]))
      return std::string("residuals_m");
  return std::nullopt;
}

}  // namespace

Result<geometry::PhysicalTableFit> parse_calibration_json(const std::string& text, const std::string& file) {
  // `line`: the place when no member names it (0: none known).
  const auto bad = [&](const std::string& key, std::string m, std::size_t line = 0) {
    if (!key.empty()) line = line_of_key(text, key);
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on
    // `":" + std::to_string(…)`.
    std::string where;
    if (!file.empty()) {
      where = file;
      if (line > 0) where.append(":").append(std::to_string(line));
      where += ": ";
    }
    if (!key.empty()) where.append(key).append(": ");
    return Error{Error::Kind::bad_input, where + std::move(m)};
  };
  if (const auto fault = find_invalid_utf8(text))
    return bad("", "the calibration file is " + utf8_fault_text(*fault), fault->line);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte: the 1-based position of the last byte read.
    const auto at = std::min(e.byte > 0 ? e.byte - 1 : 0, text.size());
    return bad("", "not valid JSON here (a syntax error)", line_at(text, at));
  } catch (const nlohmann::json::out_of_range& e) {
    // "number overflow parsing '1e400'": the number names the place.
    const std::string what = e.what();
    const auto open = what.find('\'');
    const auto close = what.rfind('\'');
    const auto at = open < close ? text.find(what.substr(open + 1, close - open - 1)) : std::string::npos;
    return bad("", "not valid JSON here (a number too large for a double)",
               at == std::string::npos ? 0 : line_at(text, at));
  }
  if (!j.is_object()) return bad("", "expected a JSON object with centre_x_m, centre_z_m, yaw_rad, edge_m, height_m");
  geometry::PhysicalTableFit fit;
  try {
    fit.centre_m = {j.at("centre_x_m").get<double>(), j.at("centre_z_m").get<double>()};
    fit.yaw_rad = j.at("yaw_rad").get<double>();
    fit.edge_m = j.at("edge_m").get<double>();
    fit.height_m = j.at("height_m").get<double>();
    fit.rms_residual_m = j.value("rms_residual_m", 0.0);
    fit.max_residual_m = j.value("max_residual_m", 0.0);
    fit.corners_used = j.value("corners_used", 0);
    const auto residuals = j.value("residuals_m", std::vector<double>{});
    if (residuals.size() > 4 || fit.corners_used < 0 || fit.corners_used > 4)
      return bad("corners_used", "must lie in 0 … 4, with at most one residual each in residuals_m");
    std::copy(residuals.begin(), residuals.end(), fit.corner_residual_m.begin());
  } catch (const nlohmann::json::exception& e) {
    return bad("", std::string(e.what()) + " (expected numbers centre_x_m, centre_z_m, yaw_rad, edge_m, height_m)");
  }
  if (const auto key = calibration_out_of_range(fit)) {
    for (const auto& r : kCalibrationRanges)
      if (*key == r.key) {
        const auto& v = j.at(r.key);
        return bad(*key, std::string("expected ") + r.expected + ", got " + v.dump());
      }
  }
  return fit;
}

Placement place_stimulus(const World& world, const Settings& s, const Isometry& head_at_onset) {
  Placement p;
  for (const StimulusKind* kind : stimulus_kinds()) kind->place(world, s, head_at_onset, p);
  return p;
}

Isometry standing_head(const World& world, const Settings& s) {
  auto tracker = geometry::make_tracker(s.tracking, world.space, world.table,
                                        physical_table(s, std::nullopt));
  return tracker->update(standing_pose(nominal_calibration(s), TrajectoryOptions{}.eye_height_m, 0)).pose[0];
}

geometry::ViewPreset perceived_preset(const Settings& s) {
  return renderer::perceived_preset(s.viewing.projection, s.viewing.eyes);
}

renderer::ViewSettings view_settings(const Settings& s, renderer::Eye dominant) {
  renderer::ViewSettings v;
  v.projection = s.viewing.projection;
  v.eyes = s.viewing.eyes;
  v.dominant_eye = dominant;
  v.back_hemisphere = s.viewing.back_hemisphere;
  return v;
}

std::string view_name(const Settings& s) {
  const geometry::ViewPreset preset = perceived_preset(s);
  switch (s.viewing.projection) {
    case renderer::Projection::tourist:
      // One tourist eye is perceived as monocular, but no preset names it.
      if (preset == geometry::ViewPreset::monocular) return "custom";
      break;
    case renderer::Projection::native: break;
  }
  return std::string(geometry::to_string(preset));
}

std::vector<Point> judged_points(const World& world, const Settings& s, const Placement& placement) {
  return judged_kind(s).judged_points(world, placement);
}

double perceived_sagitta_with(const World& world, const Settings& s, std::vector<Vec3> p,
                              const std::function<Vec3(const Point&)>& seen) {
  return judged_kind(s).perceived_sagitta_m(world, std::move(p), seen);
}

double perceived_sagitta_m(const World& world, const Settings& s, const Placement& placement,
                           const Isometry& head) {
  const geometry::ViewPreset preset = perceived_preset(s);
  if (!geometry::binocular(preset)) return 0.0;
  const auto eyes = geometry::eyes_from_ipd(s.viewing.ipd_m);
  const auto seen = [&](const Point& q) {
    return geometry::perceive_point(world.space, head, eyes, preset, q).position_m;
  };
  std::vector<Vec3> p;
  for (const Point& q : judged_points(world, s, placement)) p.push_back(seen(q));
  return perceived_sagitta_with(world, s, std::move(p), seen);
}

SightLineCount diverging_sight_lines(const World& world, const Settings& s, const Placement& placement,
                                     const Isometry& head) {
  const std::vector<Point> points = judged_points(world, s, placement);
  SightLineCount count{0, static_cast<int>(points.size())};
  if (perceived_preset(s) != geometry::ViewPreset::tourist) return count;
  const auto eyes = geometry::eyes_from_ipd(s.viewing.ipd_m);
  for (const Point& q : points) {
    const auto seen = geometry::perceive_point(world.space, head, eyes, geometry::ViewPreset::tourist, q);
    count.diverging += seen.diverging || seen.parallel ? 1 : 0;
  }
  return count;
}

double physical_sagitta_m(const Settings& s) { return judged_kind(s).physical_sagitta_m(s); }

Result<TrialScene> TrialScene::build(const World& world, const Settings& s, const std::string& prompt,
                                     const std::string& font_path, double px_per_deg) {
  TrialScene t;
  t.world_ = world;
  t.font_path_ = font_path;
  t.page_layout_ = {.text_height_deg = s.viewing.text_height_deg, .px_per_deg = px_per_deg};
  for (const StimulusKind* kind : stimulus_kinds())
    if (kind->shown(s)) t.stimuli_.push_back(kind->build(t.scene_, world, s));
  // The fixation mark is in the world, where the stimulus will be; the
  // panels are fixed to the head, above the stimulus while it is shown.
  auto mark = from_renderer(renderer::text_panel_object(world.space, "fixation", "+", font_path, 0.08, 0.08,
                                                        Isometry::identity()));
  renderer::HeadPanelLayout prompt_layout = t.page_layout_;
  prompt_layout.elevation_deg = 16.0;
  auto question = from_renderer(
      renderer::head_panel_object("prompt", prompt.empty() ? std::string(" ") : prompt, font_path, prompt_layout));
  auto page = from_renderer(renderer::head_panel_object("page", " ", font_path, t.page_layout_));
  for (auto [made, index] : {std::pair{&mark, &t.fixation_}, std::pair{&question, &t.prompt_},
                             std::pair{&page, &t.page_}}) {
    if (!*made) return made->error();  // the font: io
    auto panel = std::move(*made).value();
    panel.visible = false;
    *index = t.scene_.add(std::move(panel));
  }
  return t;
}

void TrialScene::place(const Placement& placement, const Isometry& head_at_onset) {
  const auto& space = world_.space;
  for (auto& stimulus : stimuli_) stimulus->place(scene_, placement);
  scene_.edit(fixation_).pose = head_at_onset * geometry::translation_m(space, Vec3(0.0, 0.0, -1.2));
}

void TrialScene::set_stimulus(const Settings& s, const Placement& placement) {
  for (auto& stimulus : stimuli_) stimulus->set_stimulus(scene_, s, placement);
}

void TrialScene::update(std::int64_t t_ns, const FramePoses& poses) {
  for (auto& stimulus : stimuli_) stimulus->update(scene_, t_ns, poses);
}

void TrialScene::show(Phase phase, bool stimulus_during_response) {
  const bool stimulus =
      phase == Phase::stimulus || (phase == Phase::response && stimulus_during_response);
  auto set = [&](std::size_t i, bool v) {
    if (scene_.objects()[i].visible != v) scene_.edit(i).visible = v;
  };
  for (auto& s : stimuli_) s->show(scene_, stimulus);
  set(fixation_, phase == Phase::fixation);
  set(prompt_, phase == Phase::response);
  set(page_, phase == Phase::instructions || phase == Phase::break_page || phase == Phase::done);
}

Result<Done> TrialScene::set_page(const std::string& text) {
  if (text == page_text_) return Done{};
  auto made = from_renderer(
      renderer::head_panel_object("page", text.empty() ? std::string(" ") : text, font_path_, page_layout_));
  if (!made) return made.error();  // the font: io
  auto& o = made.value();
  scene_.replace_mesh(page_, std::move(o.build), std::move(o.info), std::move(o.text));
  page_text_ = text;
  return Done{};
}

Result<Done> TrialScene::show_page(const std::string& text) {
  if (auto set = set_page(text); !set) return set;
  if (!scene_.objects()[page_].visible) scene_.edit(page_).visible = true;
  return Done{};
}

std::optional<SceneKind> parse_scene_kind(std::string_view text) {
  for (const SceneKind kind : {SceneKind::stick, SceneKind::table, SceneKind::billiards, SceneKind::tiling})
    if (text == to_string(kind)) return kind;
  return std::nullopt;
}

std::string_view to_string(SceneKind kind) {
  switch (kind) {
    case SceneKind::stick: return "stick";
    case SceneKind::table: return "table";
    case SceneKind::billiards: return "billiards";
    case SceneKind::tiling: return "tiling";
  }
  return "?";
}

Settings scene_settings(SceneKind kind, Settings s) {
  auto& st = s.stimulus;
  switch (kind) {
    case SceneKind::stick:
      // Head-locked, across the line of sight below eye level.
      st.show_stick = true;
      st.show_table = false;
      st.balls = 0;
      st.stick_anchor = protocol::StickAnchor::head;
      st.stick_distance_m = 0.75;
      st.stick_height_m = -0.25;
      break;
    case SceneKind::table:
    case SceneKind::tiling:
      st.show_stick = false;
      st.show_table = true;
      st.balls = 0;
      break;
    case SceneKind::billiards:
      // Three balls, and the stick lying across the table between them and
      // the viewer, a little above the cloth.
      st.show_stick = true;
      st.show_table = true;
      st.balls = 3;
      st.stick_anchor = protocol::StickAnchor::table;
      st.stick_distance_m = 0.2;
      st.stick_height_m = 0.05;
      break;
  }
  return s;
}

namespace {

// The viewer outside edge 0 (facing −z toward the centre), eyes
// eye_height_m above the floor, looking down at the table's centre.
Isometry table_viewer(const World& world, const Settings& s, double eye_height_m, double yaw_rad) {
  const auto& space = world.space;
  const double back_m = world.table.apothem_m() + 0.40;
  const double up_m = eye_height_m - s.table.height_m;
  const Isometry place = geometry::translation_m(space, Vec3(0.0, 0.0, back_m)) *
                         geometry::translation_m(space, Vec3(0.0, up_m, 0.0));
  // Pitch so the table centre is straight ahead: its direction as seen from
  // the eye, through the log map (one formula for every space).
  const Vec3 dir = geometry::log_origin(space, geometry::inverse(space, place) * geometry::origin(space));
  const double pitch = std::atan2(-dir.y, -dir.z);
  return place * geometry::rotation(Vec3(0.0, 1.0, 0.0), yaw_rad) * geometry::rotation(Vec3(1.0, 0.0, 0.0), -pitch);
}

}  // namespace

Result<ViewedScene> viewed_scene(SceneKind kind, const Settings& base, const SceneView& view,
                                 const std::string& prompt, const std::string& font_path) {
  const Settings s = scene_settings(kind, base);
  auto made = make_world(s);
  if (!made) return made.error();
  const World world = std::move(made).value();
  ViewedScene out;
  out.space = world.space;
  const auto& space = world.space;
  if (kind == SceneKind::tiling) {
    renderer::add_tiling(out.scene, space);
    // Off-centre and turned, so the view is not symmetric.
    out.head = geometry::translation_m(space, Vec3(0.12, 0.07, 0.2 * space.radius_m)) *
               geometry::rotation(glm::normalize(Vec3(0.3, 1.0, 0.1)), 0.35) *
               geometry::rotation(Vec3(0.0, 1.0, 0.0), view.yaw_rad);
    return out;
  }
  auto built = TrialScene::build(world, s, prompt, font_path, view.panel_px_per_deg);
  if (!built) return built.error();
  auto& trial = built.value();
  Isometry onset_head = Isometry::identity();
  if (kind == SceneKind::stick) {
    out.head = geometry::rotation(Vec3(0.0, 1.0, 0.0), view.yaw_rad);
  } else {
    out.table = world.table;
    onset_head = table_viewer(world, s, view.eye_height_m, 0.0);
    out.head = table_viewer(world, s, view.eye_height_m, view.yaw_rad);
  }
  out.placement = place_stimulus(world, s, onset_head);
  trial.place(out.placement, onset_head);
  // What a participant sees while answering: the stimulus and the prompt.
  trial.show(Phase::response, true);
  out.scene = std::move(trial.scene());
  return out;
}

}  // namespace curvlab::harness::runner
