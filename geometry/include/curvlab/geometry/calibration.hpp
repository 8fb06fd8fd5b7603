// Calibration of the physical (lab) table from corner touches.
//
// Before a session the experimenter touches the corners of the real square
// table with a tracked controller; the curved-space table is then laid over
// it so that what the participant feels and sees coincide (DESIGN.md §3, §6;
// paper, "The billiards table"). The touches are noisy, so the table is found
// by least squares: a square template (unit edge) is fitted to the touched
// corners by a 2D similarity Procrustes fit in the floor plane (rotation about
// +y, uniform scale = edge length, translation = centre); the height is the
// mean of the touches' y. The residuals say whether a touch was bad.
//
// Corner order follows table.hpp: seen from the participant standing on the
// default side (+z, looking toward −z), touch front-left, front-right,
// back-right, back-left (counter-clockwise seen from above). With yaw 0 the
// table's edge 0 faces +z, exactly like table_corner() of an E3 square.
// Three corners (the first three of that order) are enough; four are better.
#pragma once

#include "curvlab/geometry/space.hpp"
#include "curvlab/geometry/table.hpp"

#include <glm/vec2.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <variant>
#include <vector>

namespace curvlab::geometry {

// The fitted physical table in lab coordinates (metres, OpenXR STAGE frame:
// y up). Named PhysicalTableFit so it does not clash with the tracking code's
// PhysicalTable: the session runner converts this fit into that type and
// stores it with the session.
struct PhysicalTableFit {
  glm::dvec2 centre_m{0.0, 0.0};  // (x, z) of the table centre
  double yaw_rad = 0.0;           // rotation about +y taking the yaw-0 table to the lab's
  double edge_m = 0.0;            // edge length of the square (the known one, when the fit was given it)
  // The edge the touches span, fitted freely (a similarity fit): beside the
  // known edge, what the physical table measures.
  double fitted_edge_m = 0.0;
  double height_m = 0.0;          // mean y of the touched corners

  // Quality of the fit: distances between each touch and the fitted corner
  // (3D, including the height difference).
  double rms_residual_m = 0.0;
  double max_residual_m = 0.0;
  int worst_corner = -1;  // index of the touch with the largest residual
  int corners_used = 0;
  // Each touch's distance from its fitted corner, in touch order; the first
  // corners_used entries are meaningful, the rest are 0.
  std::array<double, 4> corner_residual_m{};
};

struct CalibrationLimits {
  // A touch farther than this from its fitted corner is rejected as a bad
  // touch. Controllers are tracked to a few millimetres and a careful touch
  // adds a few more, so 15 mm separates sloppiness from a wrong corner.
  double max_residual_m = 0.015;
  // Tables smaller than this are not plausible (two touches at one corner).
  double min_edge_m = 0.2;
  double max_edge_m = 5.0;
  // The table's edge as known (a protocol's [table] edge_m, which the
  // virtual table's edges must equal, or `calibrate --edge-m`): the square is
  // then fitted at that size (rotation and translation only), so a touch off
  // its corner shows in its residual instead of being absorbed by the scale;
  // and touches spanning a table whose edge differs from it by more than
  // max_edge_difference_m are refused. nullopt: the edge is fitted freely.
  std::optional<double> known_edge_m;
  double max_edge_difference_m = 0.010;
};

// Fits the square table to 3 or 4 touched corners (see the order above).
// Errors, as values: wrong count, non-finite coordinates, clockwise order,
// a set that is not a square within the limits (naming the worst corner and
// its residual), an implausible size.
std::variant<PhysicalTableFit, GeometryError> fit_square_table(
    std::span<const Vec3> corners_m, const CalibrationLimits& limits = {});

// Where corner j (0..3) of a table lies in the lab, from the fit's centre,
// yaw, edge and height (the residual fields are ignored).
Vec3 physical_table_corner(const PhysicalTableFit& table, int j);

// A simulated calibration for tests and dry runs: touches of the first
// `corner_count` corners of `truth`, each coordinate perturbed by Gaussian
// noise of standard deviation noise_sd_m, reproducible from `seed`.
std::vector<Vec3> simulate_corner_touches(const PhysicalTableFit& truth, int corner_count,
                                          double noise_sd_m, std::uint64_t seed);

}  // namespace curvlab::geometry
