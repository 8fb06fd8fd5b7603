// The binocular perception model of a Euclidean-born observer (paper,
// "Native-inhabitant view vs. tourist view" and "Mental models of space";
// DESIGN.md §5). The observer knows her eyes sit at their Euclidean offsets
// from the nose and fuses the two eye images by triangulation, as she learned
// to in the lab:
//   tourist   each eye is a curved-space translation of the nose and sees
//             along true geodesics; the observer intersects those rays as if
//             the space were flat (so H3 shrinks into a ball of radius ≈ ρ,
//             and S3 beyond ρπ/2 needs walleyed, diverging eyes);
//   native    the scene is first mapped to the nose's tangent space by the
//             azimuthal-equidistant map; the eyes are Euclidean offsets
//             there, so triangulation returns that image exactly;
//   monocular one eye, no disparity: depth comes from no binocular cue.
// These three are the view presets (DESIGN.md §4); the renderer names the
// projection and eyes each one stands for (renderer/vocabulary.hpp).
// Everything is expressed in the nose's frame: x right, y up, −z forward.
#pragma once

#include "curvlab/geometry/tube.hpp"

#include <array>
#include <optional>
#include <string_view>
#include <vector>

namespace curvlab::geometry {

enum class ViewPreset { tourist, native, monocular };
// Every preset, in the order protocols and options list them.
inline constexpr std::array kViewPresets{ViewPreset::tourist, ViewPreset::native, ViewPreset::monocular};
std::string_view to_string(ViewPreset preset);
std::optional<ViewPreset> parse_view_preset(std::string_view text);
// Whether each eye looks along true geodesics (tourist) rather than at the
// nose's azimuthal-equidistant image (native, and monocular, one native eye).
bool true_optics(ViewPreset preset);
// Whether two eyes see the scene, so that there is disparity (not monocular).
bool binocular(ViewPreset preset);

// Eye positions relative to the nose, in metres (from the runtime's views or
// from an IPD). Eye rotations relative to the head are taken as identity.
struct EyeOffsets {
  Vec3 left_m{-0.032, 0.0, 0.0};
  Vec3 right_m{0.032, 0.0, 0.0};
};
EyeOffsets eyes_from_ipd(double ipd_m);

// Where the observer perceives one point.
struct PerceivedPoint {
  // Triangulated position in the nose frame (metres): the midpoint of the
  // shortest segment between the two lines of sight, which lies behind the
  // eyes when the lines diverge. For monocular viewing, the native image.
  Vec3 position_m{0.0};
  // Sum of the two eyes' inward rotations in the plane of the eyes' axis and
  // the forward direction: positive converging, negative diverging.
  double vergence_rad = 0.0;
  bool diverging = false;      // the lines of sight meet behind the eyes
  bool parallel = false;       // no finite intersection (position is along the
                               // mean line of sight at 1e9 m)
  bool has_disparity = true;   // false for monocular viewing
};

// The lines of sight of each eye toward q (a point of the space), as seen in
// the nose frame: origin (the eye's Euclidean offset) and unit direction.
struct SightLine {
  Vec3 origin_m{0.0};
  Vec3 direction{0.0, 0.0, -1.0};
};
std::array<SightLine, 2> sight_lines(const Space& space, const Isometry& nose,
                                     const EyeOffsets& eyes, ViewPreset preset, const Point& q);

// Where two (infinite) lines o1 + s d1 and o2 + u d2 come closest: the
// midpoint of their common perpendicular and its feet's parameters. For
// parallel lines (no single closest pair) `parallel` is set and `point` is
// the midpoint of the origins.
struct LineMeeting {
  Vec3 point{0.0};
  double s = 0.0, u = 0.0;
  bool parallel = false;
};
LineMeeting closest_approach(const SightLine& a, const SightLine& b);

PerceivedPoint perceive_point(const Space& space, const Isometry& nose, const EyeOffsets& eyes,
                              ViewPreset preset, const Point& q);

// For a point straight ahead at geodesic distance d_m (symmetric eyes of
// separation ipd_m): the vergence and the distance a Euclidean observer reads
// from it, (ipd/2) / tan(vergence/2) — negative when the eyes diverge,
// +∞ when they are parallel.
struct VergenceReading {
  double vergence_rad = 0.0;
  double tourist_distance_m = 0.0;
  double native_distance_m = 0.0;
};
VergenceReading vergence_straight_ahead(const Space& space, double ipd_m, double d_m);
double distance_from_vergence_m(double vergence_rad, double ipd_m);

// A horizontal stick straight ahead at eye height, perpendicular to the line
// of sight, its midpoint at geodesic distance distance_m from the nose; its
// chord is a geodesic and it bows toward the viewer by stick.sagitta_m.
struct StickPerception {
  // Geodesic distances from the nose to the left end, left quarter point,
  // midpoint, right quarter point and right end (in that order along the stick).
  std::array<double, 5> distances_m{};
  // The perceived points, same order (nose frame).
  std::array<Vec3, 5> perceived_m{};
  // Signed distance of the perceived midpoint from the perceived chord of
  // the two ends, positive toward the viewer. Monocular: 0 (no disparity, and
  // the image of a stick bowed in depth is the same straight segment).
  double perceived_sagitta_m = 0.0;
};
// Signed distance of `middle` from the chord of end_a and end_b (all in the
// nose frame), positive toward the nose: the sagitta a viewer reads from
// three perceived points of a stick.
double bow_toward_viewer(const Vec3& end_a, const Vec3& middle, const Vec3& end_b);
// Signed height of `centre` above the plane of the polygon `rim` (through
// the vertices' centroid, with Newell's normal, robust to a rim that is not
// quite planar), positive on the side `up` points to: the bulge a viewer
// reads from the perceived edge midpoints and centre of a table top. 0 when
// the rim has no area.
double height_above_rim(const std::vector<Vec3>& rim, const Vec3& centre, const Vec3& up);

StickPerception perceive_stick(const Space& space, const BentStick& stick, double distance_m,
                               const EyeOffsets& eyes, ViewPreset preset);

// The stick's frame: the nose at the origin facing −z, the stick's chord the
// x axis of the returned frame, +z toward the viewer.
Isometry stick_frame(const Space& space, double distance_m);

}  // namespace curvlab::geometry
