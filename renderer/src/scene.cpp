#include "curvlab/renderer/scene.hpp"

#include "curvlab/renderer/tiling.hpp"

#include <atomic>
#include <cmath>
#include <memory>
#include <numbers>

namespace curvlab::renderer {

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
  return ball_object(space, radius_m, colour, pose, std::nullopt);
}

SceneObject ball_object(const Space& space, double radius_m, const glm::vec4& colour, const Isometry& pose,
                        const std::optional<glm::vec4>& marking) {
  SceneObject o;
  o.name = "ball";
  o.build = [space, radius_m, colour, marking](int) { return build_ball(space, radius_m, colour, marking); };
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
  return image_panel_object(space, std::move(name), std::move(std::get<CoverageBitmap>(bmp)), width_m, height_m,
                            pose);
}

SceneObject image_panel_object(const Space& space, std::string name, CoverageBitmap image, double width_m,
                               double height_m, const Isometry& pose) {
  SceneObject o;
  o.name = std::move(name);
  o.build = [space, width_m, height_m](int level) { return build_panel(space, width_m, height_m, level); };
  o.info = panel_info(space, width_m, height_m);
  o.pose = pose;
  o.text = std::move(image);
  return o;
}

std::variant<SceneObject, RenderError> head_panel_object(std::string name, const std::string& text,
                                                         const std::string& font, const HeadPanelLayout& layout) {
  const double line_px = layout.text_height_deg * layout.px_per_deg;
  auto made = render_text_block(text, line_px, static_cast<int>(std::lround(layout.max_width_deg * layout.px_per_deg)),
                                font);
  if (auto* e = std::get_if<RenderError>(&made)) return *e;
  TextBlock block = std::move(std::get<TextBlock>(made));
  // A flat card facing the eyes at distance_m, its angular size the
  // bitmap's at px_per_deg (half-angles, so the edges subtend exactly that).
  const double deg = std::numbers::pi / 180.0;
  const double d = layout.distance_m;
  const double half_w = d * std::tan(0.5 * block.bitmap.width / layout.px_per_deg * deg);
  const double half_h = d * std::tan(0.5 * block.bitmap.height / layout.px_per_deg * deg);
  SceneObject o;
  o.name = std::move(name);
  o.build = [half_w, half_h](int) { return build_head_panel(half_w, half_h); };
  o.pose = Isometry{glm::dmat4(1.0)};
  o.pose.m[3] = glm::dvec4(0.0, d * std::tan(layout.elevation_deg * deg), -d, 1.0);
  o.text = std::move(block.bitmap);
  o.head_locked = true;
  o.panel_size_m = {2.0 * half_w, 2.0 * half_h};
  return o;
}

void add_tiling(Scene& scene, const Space& space) {
  for (Tiling& shell : split_into_shells(space, build_tiling(space), 4)) {
    auto tiling = std::make_shared<Tiling>(std::move(shell));
    SceneObject o;
    o.name = "tiling";
    o.build = [space, tiling](int level) { return build_tiling_mesh(space, *tiling, level); };
    o.info = tiling_info(space, *tiling);
    o.pose = Isometry::identity();
    scene.add(std::move(o));
  }
}

}  // namespace curvlab::renderer
