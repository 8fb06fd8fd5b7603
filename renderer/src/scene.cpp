#include "curvlab/renderer/scene.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/renderer/tiling.hpp"
#include "curvlab/renderer/colour.hpp"

#include <atomic>
#include <cmath>
#include <memory>
#include <numbers>

namespace curvlab::renderer {

using geometry::SpaceKind;
using geometry::Vec3;

std::uint64_t Scene::next_revision() {
  static std::atomic<std::uint64_t> counter{1};
  return counter.fetch_add(1, std::memory_order_relaxed);
}

std::size_t Scene::add(SceneObject object) {
  objects_.push_back(std::move(object));
  mesh_revisions_.push_back(next_revision());
  revision_ = next_revision();
  return objects_.size() - 1;
}

SceneObject& Scene::edit(std::size_t index) {
  revision_ = next_revision();
  return objects_.at(index);
}

void Scene::replace_mesh(std::size_t index, std::function<MeshData(int)> build, MeshInfo info,
                         std::optional<CoverageBitmap> text) {
  auto& o = objects_.at(index);
  o.build = std::move(build);
  o.info = std::move(info);
  o.text = std::move(text);
  mesh_revisions_[index] = next_revision();
  revision_ = next_revision();
}

std::optional<SceneKind> parse_scene_kind(std::string_view text) {
  if (text == "stick") return SceneKind::stick;
  if (text == "table") return SceneKind::table;
  if (text == "billiards") return SceneKind::billiards;
  if (text == "tiling") return SceneKind::tiling;
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

SceneObject stick_object(const Space& space, const geometry::BentStick& stick, const Isometry& pose,
                         StickMarks marks) {
  SceneObject o;
  o.name = "cue stick";
  o.build = [space, stick, marks](int level) { return build_stick(space, stick, level, marks); };
  o.info = stick_info(space, stick);
  o.pose = pose;
  return o;
}

SceneObject table_object(const Space& space, const geometry::TableShape& table,
                         const TableStyle& style) {
  SceneObject o;
  o.name = "table";
  o.build = [space, table, style](int level) { return build_table(space, table, level, style); };
  o.info = table_info(space, table, style);
  o.pose = Isometry::identity();
  return o;
}

SceneObject ball_object(const Space& space, double radius_m, const glm::vec4& colour,
                        const Isometry& pose) {
  SceneObject o;
  o.name = "ball";
  o.build = [space, radius_m, colour](int) { return build_ball(space, radius_m, colour); };
  o.info = ball_info(space, radius_m);
  o.pose = pose;
  return o;
}

std::variant<SceneObject, RenderError> text_panel_object(const Space& space, std::string name,
                                                         const std::string& text,
                                                         const std::string& font, double width_m,
                                                         double height_m, const Isometry& pose) {
  const int w = 1024;
  const int h = static_cast<int>(std::lround(w * height_m / width_m));
  auto bmp = render_text(text, w, h, h / 2.5, font);
  if (auto* e = std::get_if<RenderError>(&bmp)) return *e;
  SceneObject o;
  o.name = std::move(name);
  o.build = [space, width_m, height_m](int level) {
    return build_panel(space, width_m, height_m, level);
  };
  o.info = panel_info(space, width_m, height_m);
  o.pose = pose;
  o.text = std::move(std::get<CoverageBitmap>(bmp));
  return o;
}

namespace {

constexpr double kTableHeightM = 0.80;

std::variant<Done, RenderError> add_panel(Scene& scene, const Space& space, const std::string& text,
                                          const std::string& font, double width_m, double height_m,
                                          const Isometry& pose) {
  auto made = text_panel_object(space, "prompt", text, font, width_m, height_m, pose);
  if (auto* e = std::get_if<RenderError>(&made)) return *e;
  scene.add(std::move(std::get<SceneObject>(made)));
  return Done{};
}

// The participant stands outside edge 0 (facing −z toward the centre) and
// looks down at the table centre.
Isometry table_viewer(const Space& space, const geometry::TableShape& table, double eye_height_m,
                      double yaw_rad) {
  const double back_m = table.apothem_m() + 0.40;
  const double up_m = eye_height_m - kTableHeightM;
  const Isometry place = geometry::translation_m(space, Vec3(0.0, 0.0, back_m)) *
                         geometry::translation_m(space, Vec3(0.0, up_m, 0.0));
  // Pitch so the table centre is straight ahead: its direction as seen from
  // the eye, through the log map (one formula for every space).
  const Vec3 dir = geometry::log_origin(space, geometry::inverse(space, place) *
                                                   geometry::origin(space));
  const double pitch = std::atan2(-dir.y, -dir.z);
  return place * geometry::rotation(Vec3(0.0, 1.0, 0.0), yaw_rad) *
         geometry::rotation(Vec3(1.0, 0.0, 0.0), -pitch);
}

}  // namespace

std::variant<StimulusScene, RenderError> make_stimulus_scene(SpaceKind kind, SceneKind scene_kind,
                                                             const StimulusOptions& options) {
  StimulusScene s;
  const int sides = geometry::default_table_sides(kind);
  std::variant<geometry::TableShape, geometry::GeometryError> table;
  if (options.radius_m) {
    table = geometry::right_angled_table_from_radius(Space{kind, *options.radius_m}, sides,
                                                     options.table_edge_m);
  } else {
    table = geometry::right_angled_table_from_edge(kind, options.table_edge_m, sides, 1.0);
  }
  if (auto* e = std::get_if<geometry::GeometryError>(&table))
    return RenderError{RenderError::Kind::stimulus, e->message};
  s.space = Space{kind, std::get<geometry::TableShape>(table).radius_m};
  const auto& shape = std::get<geometry::TableShape>(table);
  const Space& space = s.space;
  const geometry::BentStick stick{options.stick_length_m, options.stick_sagitta_m,
                                  options.stick_radius_m};

  switch (scene_kind) {
    case SceneKind::stick: {
      // The stick alone, across the line of sight below eye level, bowed
      // toward the participant by a positive sagitta (model +z faces them).
      s.head = geometry::rotation(Vec3(0.0, 1.0, 0.0), options.yaw_rad);
      s.scene.add(stick_object(space, stick, geometry::translation_m(space, Vec3(0.0, -0.25, -0.75)),
                               options.stick_marks));
      auto added = add_panel(s.scene, space, options.prompt, options.font_path, 0.9, 0.26,
                             geometry::translation_m(space, Vec3(0.0, 0.22, -1.1)));
      if (auto* e = std::get_if<RenderError>(&added)) return *e;
      break;
    }
    case SceneKind::table:
    case SceneKind::billiards: {
      s.table = shape;
      s.scene.add(table_object(space, shape));
      s.head = table_viewer(space, shape, options.eye_height_m, options.yaw_rad);
      if (scene_kind == SceneKind::table) break;
      // Fifteen balls racked toward the far side, the cue ball toward the
      // participant, the stick aimed at it, and the prompt beyond the table.
      const double r = options.ball_radius_m;
      const double rack_z = -0.35 * shape.apothem_m();
      const double cue_z = 0.45 * shape.apothem_m();
      auto place = [&](double x, double z) {
        return geometry::translation_m(space, Vec3(x, 0.0, z)) *
               geometry::translation_m(space, Vec3(0.0, r, 0.0));
      };
      const glm::vec4 colors[] = {display(0.95f, 0.80f, 0.10f), display(0.10f, 0.25f, 0.80f),
                                  display(0.85f, 0.10f, 0.10f), display(0.45f, 0.10f, 0.55f),
                                  display(0.95f, 0.45f, 0.05f), display(0.05f, 0.50f, 0.20f),
                                  display(0.55f, 0.10f, 0.10f), display(0.05f, 0.05f, 0.05f)};
      int n = 0;
      for (int row = 0; row < 5; ++row)
        for (int i = 0; i <= row; ++i, ++n) {
          const double x = (i - row / 2.0) * 2.0 * r * 1.01;
          const double z = rack_z - row * std::sqrt(3.0) * r * 1.01;
          SceneObject o = ball_object(space, r, colors[n % 8], place(x, z));
          o.name = "ball " + std::to_string(n + 1);
          s.scene.add(std::move(o));
        }
      SceneObject cue = ball_object(space, r, display(0.95f, 0.95f, 0.92f), place(0.0, cue_z));
      cue.name = "cue ball";
      s.scene.add(std::move(cue));
      // Stick along −z (model +x rotated by +90° about y), tip just behind the
      // cue ball, raised a little toward the butt.
      const double half = stick.length_m / 2.0;
      const double tilt = -0.12;
      s.scene.add(stick_object(space, stick,
                               geometry::translation_m(space, Vec3(0.0, r, cue_z + r + 0.02)) *
                                   geometry::rotation(Vec3(1.0, 0.0, 0.0), tilt) *
                                   geometry::translation_m(space, Vec3(0.0, 0.0, half)) *
                                   geometry::rotation(Vec3(0.0, 1.0, 0.0), std::numbers::pi / 2.0)));
      auto added = add_panel(s.scene, space, options.prompt, options.font_path, 0.9, 0.26,
                             geometry::translation_m(space, Vec3(0.0, 0.30, -shape.apothem_m() - 0.1)) *
                                 geometry::rotation(Vec3(1.0, 0.0, 0.0), -0.3));
      if (auto* e = std::get_if<RenderError>(&added)) return *e;
      break;
    }
    case SceneKind::tiling: {
      // Shells by distance, each its own object with its own subdivision.
      for (Tiling& shell : split_into_shells(space, build_tiling(space), 4)) {
        auto tiling = std::make_shared<Tiling>(std::move(shell));
        SceneObject o;
        o.name = "tiling";
        o.build = [space, tiling](int level) { return build_tiling_mesh(space, *tiling, level); };
        o.info = tiling_info(space, *tiling);
        o.pose = Isometry::identity();
        s.scene.add(std::move(o));
      }
      // Off-centre and turned, so the view is not symmetric.
      s.head = geometry::translation_m(space, Vec3(0.12, 0.07, 0.2 * space.radius_m)) *
               geometry::rotation(glm::normalize(Vec3(0.3, 1.0, 0.1)), 0.35) *
               geometry::rotation(Vec3(0.0, 1.0, 0.0), options.yaw_rad);
      break;
    }
  }
  return s;
}

}  // namespace curvlab::renderer
