// The billiards table: the regular n-gon with 90° corners of the trial's
// world (paper, "Construction of the billiards tables"), its cloth raised or
// lowered by the table's sagitta, and the protocol's balls on it; judged by
// its edge midpoints and its (possibly raised) centre.
#include "curvlab/harness/runner/stimulus_kind.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/renderer/mesh.hpp"

namespace curvlab::harness::runner {
namespace {

using geometry::Isometry;
using geometry::Point;
using geometry::Vec3;
using protocol::Settings;

renderer::SceneObject hidden(renderer::SceneObject o) {
  o.visible = false;
  return o;
}

renderer::SceneObject cloth(const World& world, double sagitta_m) {
  renderer::TableStyle style;
  style.cloth_sagitta_m = sagitta_m;
  return renderer::table_object(world.space, world.table, style);
}

class TableObjects final : public StimulusObjects {
 public:
  TableObjects(renderer::Scene& scene, const World& world, const Settings& s) : world_(world) {
    const auto& st = s.stimulus;
    const auto& space = world.space;
    table_ = scene.add(hidden(cloth(world, st.table_sagitta_m)));
    sagitta_m_ = st.table_sagitta_m;
    // Balls in a row across the far half of the cloth, 3 radii apart, the
    // first one white (colours as display values, renderer/colour.hpp).
    const double r = st.ball_radius_m;
    const double z = -0.3 * world.table.apothem_m();
    for (std::int64_t i = 0; i < st.balls; ++i) {
      const glm::vec4 colour =
          i == 0 ? renderer::display(0.95f, 0.95f, 0.92f) : renderer::display(0.85f, 0.12f, 0.10f);
      const double x = (static_cast<double>(i) - 0.5 * static_cast<double>(st.balls - 1)) * 3.0 * r;
      balls_.push_back(scene.add(hidden(renderer::ball_object(
          space, r, colour,
          geometry::translation_m(space, Vec3(x, 0.0, z)) * geometry::translation_m(space, Vec3(0.0, r, 0.0))))));
    }
  }

  // The table is the world's: it stands at the origin whatever the head.
  void place(renderer::Scene&, const Placement&) override {}

  void set_stimulus(renderer::Scene& scene, const Settings& s, const Placement&) override {
    if (s.stimulus.table_sagitta_m == sagitta_m_) return;
    auto o = cloth(world_, s.stimulus.table_sagitta_m);
    scene.replace_mesh(table_, std::move(o.build), std::move(o.info));
    sagitta_m_ = s.stimulus.table_sagitta_m;
  }

  void update(renderer::Scene&, std::int64_t, const FramePoses&) override {}

  void show(renderer::Scene& scene, bool visible) override {
    auto set = [&](std::size_t i) {
      if (scene.objects()[i].visible != visible) scene.edit(i).visible = visible;
    };
    set(table_);
    for (const auto b : balls_) set(b);
  }

 private:
  World world_;
  std::size_t table_ = 0;
  std::vector<std::size_t> balls_;
  double sagitta_m_ = 0.0;
};

class TableKind final : public StimulusKind {
 public:
  std::string_view name() const override { return "table"; }
  bool shown(const Settings& s) const override { return s.stimulus.show_table; }

  void place(const World&, const Settings& s, const Isometry&, Placement& p) const override {
    p.table_sagitta_m = s.stimulus.table_sagitta_m;
  }

  std::unique_ptr<StimulusObjects> build(renderer::Scene& scene, const World& world,
                                         const Settings& s) const override {
    return std::make_unique<TableObjects>(scene, world, s);
  }

  // The edge midpoints, then the (possibly raised) centre.
  std::vector<Point> judged_points(const World& world, const Placement& placement) const override {
    const auto& space = world.space;
    std::vector<Point> points;
    for (int e = 0; e < world.table.sides; ++e)
      points.push_back(geometry::table_edge_frame(space, world.table, e, world.table.edge_m / 2.0).m *
                       geometry::origin(space));
    points.push_back(geometry::translation_m(space, Vec3(0.0, placement.table_sagitta_m, 0.0)).m *
                     geometry::origin(space));
    return points;
  }
  // The centre.
  std::size_t fixated_point(std::size_t points) const override { return points - 1; }

  // The table top: its (possibly raised) centre against the plane of the
  // perceived edge midpoints, oriented by the perceived up.
  double perceived_sagitta_m(const World& world, std::vector<Vec3> p,
                             const std::function<Vec3(const Point&)>& seen) const override {
    const auto& space = world.space;
    const Vec3 centre = p.back();
    p.pop_back();
    const Vec3 flat_centre = seen(geometry::origin(space));
    const Vec3 above = seen(geometry::translation_m(space, Vec3(0.0, 0.1, 0.0)).m * geometry::origin(space));
    return geometry::height_above_rim(p, centre, above - flat_centre);
  }
  double physical_sagitta_m(const Settings& s) const override { return s.stimulus.table_sagitta_m; }

  std::vector<std::string_view> record_settings() const override {
    return {"stimulus.table_sagitta_m", "stimulus.show_table"};
  }
};

}  // namespace

const StimulusKind& table_stimulus_kind() {
  static const TableKind kind;
  return kind;
}

}  // namespace curvlab::harness::runner
