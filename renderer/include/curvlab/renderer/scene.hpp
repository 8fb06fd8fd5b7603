// What is drawn: objects with a mesh builder (per subdivision level), the
// level-independent facts the plan needs, and a pose in the world. The scene
// counts its revisions so an unchanged headless frame is not re-rendered.
#pragma once

#include "curvlab/renderer/error.hpp"
#include "curvlab/renderer/mesh.hpp"
#include "curvlab/renderer/text.hpp"

#include <glm/vec2.hpp>

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
  // model → world; for head-locked objects model → the nose, a Euclidean
  // rigid motion in lab metres acting on (x, y, z, 1).
  Isometry pose;
  glm::vec4 tint{1.0f};
  bool visible = true;
  std::optional<CoverageBitmap> text;  // text panels only
  // Fixed to the head and drawn over the curved scene with each eye's
  // Euclidean perspective: the same size, never mirrored or culled, in every
  // space and view (instructions, prompts, answers).
  bool head_locked = false;
  // A head-locked panel's width × height in metres (its card at pose), for a
  // display that shows it as a layer of its own (OpenXR quad layers).
  glm::dvec2 panel_size_m{0.0};
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

// The stimulus's objects (model frames as in mesh.hpp), from which the
// session runner builds its trial scenes (harness runner/stimulus.hpp).
SceneObject stick_object(const Space& space, const geometry::BentStick& stick, const Isometry& pose,
                         StickMarks marks = StickMarks::none);
SceneObject table_object(const Space& space, const geometry::TableShape& table,
                         const TableStyle& style = {});
SceneObject ball_object(const Space& space, double radius_m, const glm::vec4& colour, const Isometry& pose,
                        const std::optional<glm::vec4>& marking);
SceneObject ball_object(const Space& space, double radius_m, const glm::vec4& colour,
                        const Isometry& pose);
// A text panel of width × height metres (about 1000 px per metre), or a
// RenderError of kind `font` when the font cannot be read.
std::variant<SceneObject, RenderError> text_panel_object(const Space& space, std::string name,
                                                         const std::string& text,
                                                         const std::string& font, double width_m,
                                                         double height_m, const Isometry& pose);

// A panel of width × height metres showing `image` (ink coverage over
// paper, stretched to the panel): a picture in the world, e.g. a face.
SceneObject image_panel_object(const Space& space, std::string name, CoverageBitmap image, double width_m,
                               double height_m, const Isometry& pose);

// Where a head-locked text panel sits and how large its text is, in visual
// angle: a participant reads it at the same size in S3, E3 and H3.
struct HeadPanelLayout {
  double text_height_deg = 2.0;   // a line of text, ascent to descent
  double max_width_deg = 44.0;    // longer lines are broken at spaces
  double elevation_deg = 0.0;     // the centre above (+) or below the line of sight
  double distance_m = 1.5;        // where the eyes converge on it
  double px_per_deg = 16.0;       // texels per degree: at least the display's pixels
};

// A head-locked text panel (SceneObject::head_locked) sized to its text, or
// a RenderError of kind `font`.
std::variant<SceneObject, RenderError> head_panel_object(std::string name, const std::string& text,
                                                         const std::string& font, const HeadPanelLayout& layout);

// The space's honeycomb (tiling.hpp), in shells by distance, each its own
// object with its own subdivision: a debug scene of the renderer's.
void add_tiling(Scene& scene, const Space& space);

}  // namespace curvlab::renderer
