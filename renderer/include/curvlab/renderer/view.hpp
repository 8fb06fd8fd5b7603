// View math, pure and in double: eye model, the tourist and native pipelines
// (paper, sections "Computer graphics in curved space" and "Native-inhabitant
// view vs. tourist view"), the projection, the S3 back hemisphere, and the
// screen-space error of a subdivided geodesic. The vertex shader mirrors
// clip_position() in float (shaders/curved.glsl; the formula_parity test
// compares them).
#pragma once

#include "curvlab/geometry/isometry.hpp"
#include "curvlab/renderer/vocabulary.hpp"

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>

#include <array>
#include <optional>

namespace curvlab::renderer {

using geometry::Isometry;
using geometry::Point;
using geometry::Space;
using geometry::ViewPreset;

enum class Eye { left = 0, right = 1 };
enum class Hemisphere { front = 0, back = 1 };

// Projection and eyes are separate settings; the presets are names for
// common pairs (vocabulary.hpp, preset_viewing).
struct ViewSettings {
  Projection projection = Projection::native;
  EyeSelection eyes = EyeSelection::both;
  Eye dominant_eye = Eye::right;
  bool back_hemisphere = true;  // S3 only; a confound control when off
  double near_m = 0.05;
  // Largest screen-space deviation of a drawn geodesic edge from the true
  // curve, in pixels, that native subdivision may leave.
  double error_budget_px = 0.1;
  // Fixes the native subdivision level instead (benchmarks, replays).
  std::optional<int> forced_level;

  static ViewSettings preset(ViewPreset preset);
  [[nodiscard]] bool shows(Eye eye) const;
};

// Field of view as OpenXR gives it (XrFovf): angles from the view axis,
// left and down negative.
struct Fov {
  double angle_left_rad = -0.785398;
  double angle_right_rad = 0.785398;
  double angle_up_rad = 0.785398;
  double angle_down_rad = -0.785398;

  static Fov symmetric(double horizontal_rad, double aspect_w_over_h);
};

// One eye relative to the nose (the head pose), in lab metres, as OpenXR
// views give it after subtracting the head pose.
struct EyeOffset {
  glm::dvec3 position_m{0.0};
  glm::dmat3 rotation{1.0};
  Fov fov;
};

struct StereoRig {
  std::array<EyeOffset, 2> eyes;
  // Eyes ±ipd/2 along the head's x axis, parallel, with the same FOV.
  static StereoRig from_ipd(double ipd_m, const Fov& fov);
};

// What one eye's view needs, in double (uploaded as float).
struct ViewConstants {
  Projection projection = Projection::tourist;
  Space space;
  Fov fov;  // the eye's, for culling
  glm::dmat4 proj_front{1.0};
  glm::dmat4 proj_back{1.0};
  // Native only: the Euclidean eye offset in the nose's tangent space,
  // e = Rᵀ(q − t) as a 4×4 acting on (q, 1).
  glm::dmat4 eye_from_nose{1.0};
  // The viewer the model-view matrices are relative to: the eye (tourist) or
  // the nose (native).
  Isometry viewer_from_world;
};

// w/(−z) for a point straight ahead at distance t radians: C(t)/S(t), which
// falls monotonically with t in every space (DESIGN.md §4).
double projective_depth(const Space& space, double t_rad);

// The asymmetric perspective matrix acting on (x, y, z, w) with clip.w = −z
// and z_ndc = A + B·w/(−z) running from depth_lo at c_near to depth_hi at
// c_far (Vulkan conventions: y down, depth 0…1).
glm::dmat4 projection_matrix(const Fov& fov, double c_near, double c_far, double depth_lo,
                             double depth_hi);

// The per-eye constants. head: the nose pose in the world. The tourist eye is
// a curved-space translation of the nose; the native eye a Euclidean offset in
// the nose's tangent space (paper, section "Native-inhabitant view…").
ViewConstants make_view_constants(const Space& space, const ViewSettings& settings,
                                  const Isometry& head, const EyeOffset& eye);

// CPU twin of the vertex shader's curv_clip: p is viewer-relative.
glm::dvec4 clip_position(const ViewConstants& view, Hemisphere hemi, const Point& p_viewer);

// Clip → pixel coordinates for a target of the given size (pixel centres at
// .5); nullopt behind the eye (clip.w ≤ 0).
std::optional<glm::dvec2> to_pixels(const glm::dvec4& clip, double width_px, double height_px);

// A geodesic edge in model coordinates (its endpoints).
struct GeodesicEdge {
  Point a;
  Point b;
};

// Screen-space error of drawing `edge` (transformed by model_view) as
// `segments` straight pieces: the largest and mean distance in pixels of the
// true curve (sampled `samples_per_segment` times per piece) from the drawn
// polyline. Pieces with a point behind the eye are skipped.
struct EdgeError {
  double max_px = 0.0;
  double mean_px = 0.0;
  int samples = 0;
};
EdgeError edge_screen_error(const ViewConstants& view, Hemisphere hemi,
                            const glm::dmat4& model_view, const GeodesicEdge& edge, int segments,
                            double width_px, double height_px, int samples_per_segment = 8);

}  // namespace curvlab::renderer
