// An observer that reads the rendered images (DESIGN.md §4 "Stimulus
// fidelity", §5): the cue stick's perceived sagitta estimated from the left
// and right images alone. The stick's rings (renderer/mesh.hpp, StickMarks)
// are found in both eyes by coverage-weighted centroids along the stick, the
// matched image points are triangulated with the recorded eye poses and
// projections (least-squares intersection of the two lines of sight in the
// viewer's Euclidean frame — what a Euclidean-born visual system assumes,
// geometry/perception.hpp), and a curve through the triangulated points
// (the offset from their chord a quadratic along the chord) gives the stick's
// ends and middle, whose bow toward the viewer is the estimate. Sign: positive bows toward the viewer (convex), as the
// perception model and the protocols count it.
//
// The perception model computes the same quantity from the scene's geometry;
// the two check each other: the renderer draws what the model predicts, and
// the model predicts what the pixels carry.
#pragma once

#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/geometry/tube.hpp"
#include "curvlab/harness/result.hpp"
#include "curvlab/renderer/image_io.hpp"
#include "curvlab/renderer/mesh.hpp"
#include "curvlab/renderer/view.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::measure {

// What the observer knows besides the images: its own eyes (pose relative to
// the nose, projection, image size) and the stick's marking and thickness.
// The stick's pose and bend and the space serve only the model's value.
struct StickScene {
  geometry::Space space;
  geometry::ViewPreset preset = geometry::ViewPreset::native;
  geometry::Isometry head;  // the nose in the world
  renderer::StereoRig rig;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  geometry::BentStick stick;
  geometry::Isometry stick_pose;  // model → world: chord along x, bow toward +z
  renderer::StickMarks marks = renderer::StickMarks::none;
};

// The record of a StickScene (plan.json "measure", the runner's onset
// sidecar), and back; parsing names the missing or malformed field.
nlohmann::ordered_json scene_json(const StickScene& scene);
Result<StickScene> parse_scene_json(const nlohmann::json& j);

// One ring seen in both eyes.
struct StickFeature {
  std::string name;        // "ring -0.4" … (fraction of the length from the middle)
  double u_m = 0.0;        // axial position along the stick (metres from the middle)
  glm::dvec2 left_px{0.0};   // image positions (pixel centres at .5)
  glm::dvec2 right_px{0.0};
  geometry::Vec3 position_m{0.0};  // triangulated centre line point, nose frame
  double residual_left_px = 0.0;   // reprojection residuals of the triangulated point
  double residual_right_px = 0.0;
  int rows = 0;  // image rows averaged per eye (the smaller of the two)
  double depth_radii = 0.0;  // in front of the centre line (mean of the two eyes)
  // The stick's radius as seen: its angular half-thickness in the images at
  // the triangulated distance (mean of the two eyes).
  double radius_seen_m = 0.0;
};

struct StickEstimate {
  // The middle's distance from the chord of the ends along the normal that
  // points from the chord toward the nose (the perception model's measure).
  double estimated_sagitta_m = 0.0;
  double model_sagitta_m = 0.0;
  // The middle's whole distance from the chord, signed as the sagitta: the
  // bend in the stick's own plane (the shown bend, for a Euclidean view of a
  // stick below or above the eyes, whose bend plane the sagitta sees tilted).
  double estimated_bend_m = 0.0;
  double model_bend_m = 0.0;
  bool binocular = true;  // false: one eye showed no stick (no disparity, estimate 0)
  // With a human observer's limits: its percept of the rings, fixating the
  // middle one (their perceived points are the features' positions).
  std::optional<geometry::HumanPercept> human;
  double fit_rms_m = 0.0; // triangulated points against the fitted curve
  std::vector<StickFeature> features;
};

// The stick's pixels: per column, the first and last row of the widest
// 4-connected region that differs from the background (the image's border
// colour).
struct StickMask {
  int x0 = 0, x1 = -1;                // columns covered, inclusive
  std::vector<int> top, bottom;       // per column from x0; −1 where empty
  std::vector<std::uint8_t> inside;   // the region, row major
  int width = 0;
  std::uint32_t background = 0;       // the image's border colour
  [[nodiscard]] bool at(int x, int y) const {
    return inside[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)] != 0;
  }
};

// The stick in one eye's image, found once and then read for its rings; none
// when the image shows no stick (one eye of a monocular view).
std::optional<StickMask> find_stick(const renderer::Rgba8Image& image);

// The rings' image positions in one eye, in order along the stick (butt to
// tip, left to right in the image), or why they cannot be found (a ring
// missing or cut by the outline, rings too small to locate).
struct RingSighting {
  glm::dvec2 px{0.0};
  int rows = 0;  // image rows averaged
  // The rows cross the stick's visible half at sin α = (row − axis) / radius
  // (α from the line of sight); the mean of cos α over them is how far in
  // front of the centre line, in radii, the located point lies.
  double depth_radii = 0.785;
  double half_thickness_px = 0.0;  // the stick's, across the ring's window
  // How far the ring's column moves per radius of depth (d column / d cos α,
  // px): the ring's points nearer the eye lie further out along the stick's
  // image when the stick is seen obliquely. With it the two eyes' sightings
  // are compared at the same depth on the ring (at_depth), whichever rows
  // each eye happened to average.
  double px_per_depth_radius = 0.0;
  [[nodiscard]] glm::dvec2 at_depth(double radii) const {
    return px + glm::dvec2(px_per_depth_radius * (radii - depth_radii), 0.0);
  }
};
Result<std::vector<RingSighting>> find_rings(const renderer::Rgba8Image& image, const StickMask& stick,
                                             double stick_radius_m);

// The line of sight through an image point, in the nose frame.
geometry::SightLine sight_line(const renderer::EyeOffset& eye, std::uint32_t width_px,
                               std::uint32_t height_px, const glm::dvec2& px);
// Where a nose-frame point appears in an eye's image (Euclidean pinhole).
glm::dvec2 project_px(const renderer::EyeOffset& eye, std::uint32_t width_px, std::uint32_t height_px,
                      const geometry::Vec3& p_m);

// The estimate from the two images. A plain stick has no features along its
// length to match between the eyes: that is an error naming the fix (rings).
// With `vision`, the rings are perceived by the human observer
// (geometry/human_vision.hpp) instead of met exactly, and the model's
// values are the human model's.
Result<StickEstimate> measure_stick(const renderer::Rgba8Image& left, const renderer::Rgba8Image& right,
                                    const StickScene& scene, const geometry::HumanVision* vision = nullptr);

nlohmann::ordered_json estimate_json(const StickEstimate& e);

}  // namespace curvlab::harness::measure
