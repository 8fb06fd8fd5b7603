// The cue stick: a bent tube of the protocol's length, radius and sagitta,
// head-locked or across the table at onset (DESIGN.md §2, tubes in Fermi
// coordinates); judged by its ends and middle, the bow toward the viewer.
#include "curvlab/harness/runner/stimulus_kind.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/renderer/mesh.hpp"

#include <numbers>

namespace curvlab::harness::runner {
namespace {

using geometry::Isometry;
using geometry::Point;
using geometry::Vec3;
using protocol::Settings;

class StickObjects final : public StimulusObjects {
 public:
  StickObjects(renderer::Scene& scene, const World& world, const Settings& s) : space_(world.space) {
    const auto& st = s.stimulus;
    const geometry::BentStick stick{st.stick_length_m, st.stick_sagitta_m, st.stick_radius_m};
    auto o = renderer::stick_object(space_, stick, Isometry::identity(), st.stick_marks);
    o.visible = false;
    index_ = scene.add(std::move(o));
    sagitta_m_ = st.stick_sagitta_m;
    length_m_ = st.stick_length_m;
  }

  void place(renderer::Scene& scene, const Placement& placement) override {
    scene.edit(index_).pose = placement.stick_pose;
  }

  void set_stimulus(renderer::Scene& scene, const Settings& s, const Placement& placement) override {
    const auto& st = s.stimulus;
    // A new mesh only when the shape changed: a re-placed stick keeps its GPU mesh.
    if (st.stick_sagitta_m != sagitta_m_ || st.stick_length_m != length_m_) {
      auto o = renderer::stick_object(space_, placement.stick, placement.stick_pose, st.stick_marks);
      scene.replace_mesh(index_, std::move(o.build), std::move(o.info));
      sagitta_m_ = st.stick_sagitta_m;
      length_m_ = st.stick_length_m;
    }
    scene.edit(index_).pose = placement.stick_pose;
  }

  void update(renderer::Scene&, std::int64_t, const FramePoses&) override {}

  void show(renderer::Scene& scene, bool visible) override {
    if (scene.objects()[index_].visible != visible) scene.edit(index_).visible = visible;
  }

 private:
  geometry::Space space_;
  std::size_t index_ = 0;
  double sagitta_m_ = 0.0, length_m_ = 0.0;
};

class StickKind final : public StimulusKind {
 public:
  std::string_view name() const override { return "stick"; }
  bool shown(const Settings& s) const override { return s.stimulus.show_stick; }

  void place(const World& world, const Settings& s, const Isometry& head_at_onset, Placement& p) const override {
    const auto& st = s.stimulus;
    p.stick = geometry::BentStick{st.stick_length_m, st.stick_sagitta_m, st.stick_radius_m};
    const double yaw = st.stick_yaw_deg * std::numbers::pi / 180.0;
    const Isometry turn = geometry::rotation(Vec3(0.0, 1.0, 0.0), yaw);
    const auto& space = world.space;
    if (st.stick_anchor == protocol::StickAnchor::head) {
      // Head-locked at onset, then fixed in the world for the trial.
      p.stick_pose = head_at_onset *
                     geometry::translation_m(space, Vec3(0.0, st.stick_height_m, -st.stick_distance_m)) * turn;
      return;
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
                   geometry::translation_m(space, Vec3(0.0, st.stick_height_m, 0.0)) * geometry::rotation(frame) *
                   turn;
  }

  std::unique_ptr<StimulusObjects> build(renderer::Scene& scene, const World& world,
                                         const Settings& s) const override {
    return std::make_unique<StickObjects>(scene, world, s);
  }

  // The ends and the middle (end, middle, end).
  std::vector<Point> judged_points(const World& world, const Placement& placement) const override {
    std::vector<Point> points;
    const double half = placement.stick.length_m / 2.0;
    for (const double u : {-half, 0.0, half})
      points.push_back(placement.stick.centre_point(world.space, placement.stick_pose, u));
    return points;
  }
  // The middle.
  std::size_t fixated_point(std::size_t) const override { return 1; }

  double perceived_sagitta_m(const World&, std::vector<Vec3> p,
                             const std::function<Vec3(const Point&)>&) const override {
    return geometry::bow_toward_viewer(p[0], p[1], p[2]);
  }
  double physical_sagitta_m(const Settings& s) const override { return s.stimulus.stick_sagitta_m; }

  std::vector<std::string_view> record_settings() const override {
    return {"stimulus.stick_sagitta_m", "stimulus.stick_length_m", "stimulus.stick_distance_m",
            "stimulus.stick_height_m",  "stimulus.stick_anchor",   "stimulus.stick_marks",
            "stimulus.show_stick"};
  }
};

}  // namespace

const StimulusKind& stick_stimulus_kind() {
  static const StickKind kind;
  return kind;
}

}  // namespace curvlab::harness::runner
