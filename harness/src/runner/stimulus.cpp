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

Judged judged(const Settings& s) { return s.stimulus.show_stick ? Judged::stick : Judged::table; }

Placement place_stimulus(const World& world, const Settings& s, const Isometry& head_at_onset) {
  const auto& st = s.stimulus;
  Placement p;
  p.stick = geometry::BentStick{st.stick_length_m, st.stick_sagitta_m, st.stick_radius_m};
  p.table_sagitta_m = st.table_sagitta_m;
  const double yaw = st.stick_yaw_deg * std::numbers::pi / 180.0;
  const Isometry turn = geometry::rotation(Vec3(0.0, 1.0, 0.0), yaw);
  const auto& space = world.space;
  if (st.stick_anchor == protocol::StickAnchor::head) {
    // Head-locked at onset, then fixed in the world for the trial.
    p.stick_pose = head_at_onset *
                   geometry::translation_m(space, Vec3(0.0, st.stick_height_m, -st.stick_distance_m)) *
                   turn;
    return p;
  }
  // Across the table, stick_distance_m from its centre toward the viewer,
  // stick_height_m above the cloth, its +z (the bow) facing the viewer.
  Vec3 toward = geometry::log_origin(space, head_at_onset.m * geometry::origin(space));
  toward.y = 0.0;
  const double len = glm::length(toward);
  toward = len > 1e-9 ? toward / len : Vec3(0.0, 0.0, 1.0);
  const Vec3 up(0.0, 1.0, 0.0);
  const geometry::Mat3 frame(glm::cross(up, toward), up, toward);
  p.stick_pose = geometry::translation_m(space, toward * st.stick_distance_m) *
                 geometry::translation_m(space, Vec3(0.0, st.stick_height_m, 0.0)) *
                 geometry::rotation(frame) * turn;
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
  const auto& space = world.space;
  std::vector<Point> points;
  if (judged(s) == Judged::stick) {
    const double half = placement.stick.length_m / 2.0;
    for (const double u : {-half, 0.0, half})
      points.push_back(placement.stick.centre_point(space, placement.stick_pose, u));
    return points;
  }
  for (int e = 0; e < world.table.sides; ++e)
    points.push_back(geometry::table_edge_frame(space, world.table, e, world.table.edge_m / 2.0).m *
                     geometry::origin(space));
  points.push_back(geometry::translation_m(space, Vec3(0.0, placement.table_sagitta_m, 0.0)).m *
                   geometry::origin(space));
  return points;
}

double perceived_sagitta_with(const World& world, const Settings& s, std::vector<Vec3> p,
                              const std::function<Vec3(const Point&)>& seen) {
  const auto& space = world.space;
  if (judged(s) == Judged::stick) return geometry::bow_toward_viewer(p[0], p[1], p[2]);
  // The table top: its (possibly raised) centre against the plane of the
  // perceived edge midpoints, oriented by the perceived up.
  const Vec3 centre = p.back();
  p.pop_back();
  const Vec3 flat_centre = seen(geometry::origin(space));
  const Vec3 above = seen(geometry::translation_m(space, Vec3(0.0, 0.1, 0.0)).m * geometry::origin(space));
  return geometry::height_above_rim(p, centre, above - flat_centre);
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

double physical_sagitta_m(const Settings& s) {
  return judged(s) == Judged::stick ? s.stimulus.stick_sagitta_m : s.stimulus.table_sagitta_m;
}

Result<TrialScene> TrialScene::build(const World& world, const Settings& s, const std::string& prompt,
                                     const std::string& font_path) {
  TrialScene t;
  t.world_ = world;
  t.font_path_ = font_path;
  const auto& space = world.space;
  const auto& st = s.stimulus;
  auto hidden = [](renderer::SceneObject o) {
    o.visible = false;
    return o;
  };
  if (st.show_table) {
    renderer::TableStyle style;
    style.cloth_sagitta_m = st.table_sagitta_m;
    t.table_ = t.scene_.add(hidden(renderer::table_object(space, world.table, style)));
    t.has_table_ = true;
    t.table_sagitta_m_ = st.table_sagitta_m;
    // Balls in a row across the far half of the cloth, the first one white.
    const double r = st.ball_radius_m;
    const double z = -0.3 * world.table.apothem_m();
    for (std::int64_t i = 0; i < st.balls; ++i) {
      const glm::vec4 colour = i == 0 ? glm::vec4(0.95f, 0.95f, 0.92f, 1.0f)
                                      : glm::vec4(0.85f, 0.12f, 0.10f, 1.0f);
      const double x = (static_cast<double>(i) - 0.5 * static_cast<double>(st.balls - 1)) * 3.0 * r;
      t.balls_.push_back(t.scene_.add(hidden(renderer::ball_object(
          space, r, colour,
          geometry::translation_m(space, Vec3(x, 0.0, z)) * geometry::translation_m(space, Vec3(0.0, r, 0.0))))));
    }
  }
  if (st.show_stick) {
    const geometry::BentStick stick{st.stick_length_m, st.stick_sagitta_m, st.stick_radius_m};
    t.stick_ = t.scene_.add(hidden(renderer::stick_object(space, stick, Isometry::identity(), st.stick_marks)));
    t.has_stick_ = true;
    t.stick_sagitta_m_ = st.stick_sagitta_m;
    t.stick_length_m_ = st.stick_length_m;
  }
  for (auto [index, name, text, w, h] :
       {std::tuple{&t.prompt_, "prompt", prompt, 1.0, 0.22},
        std::tuple{&t.fixation_, "fixation", std::string("+"), 0.08, 0.08},
        std::tuple{&t.page_, "page", std::string(" "), 1.0, 0.5}}) {
    auto made = from_renderer(renderer::text_panel_object(space, name, text.empty() ? std::string(" ") : text,
                                                          font_path, w, h, Isometry::identity()));
    if (!made) return made.error();  // the font: io
    *index = t.scene_.add(hidden(std::move(made).value()));
  }
  return t;
}

void TrialScene::place(const Placement& placement, const Isometry& head_at_onset) {
  const auto& space = world_.space;
  if (has_stick_) scene_.edit(stick_).pose = placement.stick_pose;
  scene_.edit(prompt_).pose =
      head_at_onset * geometry::translation_m(space, Vec3(0.0, 0.32, -1.5));
  scene_.edit(fixation_).pose = head_at_onset * geometry::translation_m(space, Vec3(0.0, 0.0, -1.2));
}

void TrialScene::set_stimulus(const Settings& s, const Placement& placement) {
  const auto& space = world_.space;
  const auto& st = s.stimulus;
  if (has_stick_) {
    if (st.stick_sagitta_m != stick_sagitta_m_ || st.stick_length_m != stick_length_m_) {
      auto o = renderer::stick_object(space, placement.stick, placement.stick_pose, st.stick_marks);
      scene_.replace_mesh(stick_, std::move(o.build), std::move(o.info));
      stick_sagitta_m_ = st.stick_sagitta_m;
      stick_length_m_ = st.stick_length_m;
    }
    scene_.edit(stick_).pose = placement.stick_pose;
  }
  if (has_table_ && st.table_sagitta_m != table_sagitta_m_) {
    renderer::TableStyle style;
    style.cloth_sagitta_m = st.table_sagitta_m;
    auto o = renderer::table_object(space, world_.table, style);
    scene_.replace_mesh(table_, std::move(o.build), std::move(o.info));
    table_sagitta_m_ = st.table_sagitta_m;
  }
}

void TrialScene::show(Phase phase, bool stimulus_during_response) {
  const bool stimulus =
      phase == Phase::stimulus || (phase == Phase::response && stimulus_during_response);
  auto set = [&](std::size_t i, bool v) {
    if (scene_.objects()[i].visible != v) scene_.edit(i).visible = v;
  };
  if (has_table_) set(table_, stimulus);
  for (auto b : balls_) set(b, stimulus);
  if (has_stick_) set(stick_, stimulus);
  set(fixation_, phase == Phase::fixation);
  set(prompt_, phase == Phase::response);
  set(page_, phase == Phase::instructions || phase == Phase::break_page || phase == Phase::done);
}

Result<Done> TrialScene::set_page(const std::string& text, const Isometry& head) {
  if (text != page_text_) {
    auto made = from_renderer(renderer::text_panel_object(
        world_.space, "page", text.empty() ? std::string(" ") : text, font_path_, 1.0, 0.5, Isometry::identity()));
    if (!made) return made.error();  // the font: io
    auto& o = made.value();
    scene_.replace_mesh(page_, std::move(o.build), std::move(o.info), std::move(o.text));
    page_text_ = text;
  }
  scene_.edit(page_).pose = head * geometry::translation_m(world_.space, Vec3(0.0, 0.0, -1.2));
  return Done{};
}

}  // namespace curvlab::harness::runner
