// The render plan (DESIGN.md §4): each frame decides what it needs and skips
// the rest — only eyes that show something, the S3 back hemisphere only when
// an antipodal image can be in view, culled draws, subdivision only where
// the native view bends edges. Pure CPU code, testable without a device.
#pragma once

#include "curvlab/renderer/scene.hpp"

namespace curvlab::renderer {

// Everything about a frame except the scene and the target images.
struct FrameDescription {
  Space space;
  ViewSettings settings;
  Isometry head;  // nose pose in the world
  StereoRig rig = StereoRig::from_ipd(0.063, Fov{});
  std::uint32_t width_px = 1024;   // per eye
  std::uint32_t height_px = 1024;
  // Head-locked objects drawn over the scene; false where the display's
  // compositor shows them as layers of their own (OpenXR quad layers).
  bool draw_head_locked = true;
};

inline constexpr int kMaxSubdivisionLevel = 6;

struct PlannedDraw {
  std::size_t object = 0;
  int level = 0;
  Hemisphere hemisphere = Hemisphere::front;
  glm::dmat4 model_view{1.0};  // viewer ← model, double (uploaded as float)
  // A head-locked object: model_view is clip ← model (the eye's Euclidean
  // perspective), drawn after the scene without depth.
  bool overlay = false;
};

struct ViewPlan {
  Eye eye = Eye::left;
  bool rendered = true;  // false: the eye shows only the background
  ViewConstants constants;
  std::vector<PlannedDraw> draws;
  int culled = 0;
  double estimated_error_px = 0.0;  // worst probe edge at the chosen levels
};

struct RenderPlan {
  std::array<ViewPlan, 2> views;
  bool back_hemisphere = false;  // any back-hemisphere draw planned
  int max_level = 0;
  [[nodiscard]] int rendered_views() const;
  [[nodiscard]] std::size_t draw_count() const;
};

// True when the object (bounding ball of `radius_m` about the viewer-relative
// centre) can appear in the view for that hemisphere.
bool may_be_visible(const ViewConstants& view, Hemisphere hemi, const Point& centre,
                    double radius_m);

// The smallest subdivision level whose probe edges stay within the error
// budget (tourist: 0, since its projection keeps geodesics straight), and the
// error at that level.
std::pair<int, double> choose_level(const ViewConstants& view, Hemisphere hemi,
                                    const glm::dmat4& model_view, const MeshInfo& info,
                                    const FrameDescription& frame);

// Clip ← model for a head-locked object (SceneObject::head_locked): the
// eye's Euclidean perspective (Vulkan conventions) after its offset from
// the nose.
glm::dmat4 head_locked_clip(const EyeOffset& eye, const glm::dmat4& nose_from_model);

RenderPlan plan_frame(const Scene& scene, const FrameDescription& frame);

}  // namespace curvlab::renderer
