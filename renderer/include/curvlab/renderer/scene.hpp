// What is drawn: objects with a mesh builder (per subdivision level), the
// level-independent facts the plan needs, and a pose in the world. The scene
// counts its revisions so an unchanged headless frame is not re-rendered.
#pragma once

#include "curvlab/renderer/error.hpp"
#include "curvlab/renderer/mesh.hpp"
#include "curvlab/renderer/text.hpp"

#include <functional>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::renderer {

struct SceneObject {
  std::string name;
  std::function<MeshData(int level)> build;  // pure: same level → same mesh
  MeshInfo info;
  Isometry pose;  // model → world
  glm::vec4 tint{1.0f};
  bool visible = true;
  std::optional<CoverageBitmap> text;  // text panels only
};

// A list of objects. Not thread-safe. Every mutable access bumps revision();
// mesh_revision(i) changes only when object i's mesh or text may have changed.
// Both are drawn from one process-wide counter, so two scenes never share a
// revision: a renderer that draws one scene after another (a session builds
// one per trial) can neither reuse the other's meshes nor skip its frame.
class Scene {
 public:
  std::size_t add(SceneObject object);
  [[nodiscard]] const std::vector<SceneObject>& objects() const { return objects_; }
  // Pose, tint and visibility changes.
  SceneObject& edit(std::size_t index);
  // Replaces object i's builder/text (its GPU meshes are rebuilt).
  void replace_mesh(std::size_t index, std::function<MeshData(int)> build, MeshInfo info,
                    std::optional<CoverageBitmap> text = std::nullopt);
  [[nodiscard]] std::uint64_t revision() const { return revision_; }
  [[nodiscard]] std::uint64_t mesh_revision(std::size_t index) const { return mesh_revisions_[index]; }

 private:
  std::vector<SceneObject> objects_;
  std::vector<std::uint64_t> mesh_revisions_;
  std::uint64_t revision_ = next_revision();
  static std::uint64_t next_revision();
};

// The stimulus's objects (model frames as in mesh.hpp), shared by the
// stimulus scenes below and the session runner's trial scenes.
SceneObject stick_object(const Space& space, const geometry::BentStick& stick, const Isometry& pose,
                         StickMarks marks = StickMarks::none);
SceneObject table_object(const Space& space, const geometry::TableShape& table,
                         const TableStyle& style = {});
SceneObject ball_object(const Space& space, double radius_m, const glm::vec4& colour,
                        const Isometry& pose);
// A text panel of width × height metres (about 1000 px per metre), or a
// RenderError of kind `font` when the font cannot be read.
std::variant<SceneObject, RenderError> text_panel_object(const Space& space, std::string name,
                                                         const std::string& text,
                                                         const std::string& font, double width_m,
                                                         double height_m, const Isometry& pose);

enum class SceneKind { stick, table, billiards, tiling };
std::optional<SceneKind> parse_scene_kind(std::string_view text);
std::string_view to_string(SceneKind kind);

struct StimulusOptions {
  double table_edge_m = 0.9;   // physical edge; fixes ρ in S3 and H3
  std::optional<double> radius_m;  // overrides: the table then follows from ρ
  double eye_height_m = 1.55;  // above the floor; the cloth is at 0.80 m
  double yaw_rad = 0.0;        // head turned left (+) from facing the stimulus
  double stick_length_m = 1.0;
  double stick_radius_m = 0.0125;
  double stick_sagitta_m = 0.0;  // bend: + toward the viewer
  StickMarks stick_marks = StickMarks::none;
  double ball_radius_m = 0.0285; // 57 mm balls
  std::string prompt = "Is the cue stick bent toward you,\nstraight, or bent away?";
  std::string font_path = CURVLAB_DEFAULT_FONT;
};

struct StimulusScene {
  Space space;
  Scene scene;
  Isometry head;  // where the participant's nose is, facing the stimulus
  std::optional<geometry::TableShape> table;
};

// The stimulus scenes of the study (DESIGN.md §4). The space's radius comes
// from the table's physical edge (S3 triangle, E3 square, H3 pentagon, all
// right-angled) unless options.radius_m is given. Options that give no table
// (geometry's GeometryError) are a RenderError of kind `stimulus` with
// geometry's message; a prompt font that cannot be read, of kind `font`.
std::variant<StimulusScene, RenderError> make_stimulus_scene(geometry::SpaceKind kind,
                                                             SceneKind scene,
                                                             const StimulusOptions& options);

}  // namespace curvlab::renderer
