// Tubes (cue stick, cushions) in Fermi coordinates about a geodesic axis:
// translate along the axis, then offset perpendicular to it (DESIGN.md §2).
// A bent stick is an offset h(s) from its chord geodesic.
#pragma once

#include "curvlab/geometry/isometry.hpp"

namespace curvlab::geometry {

// The point at axial distance s_m (metres along the frame's x axis from the
// frame's origin) and perpendicular offset (offset_y_m, offset_z_m).
Point fermi_point(const Space& space, const Isometry& axis_frame, double s_m,
                  double offset_y_m, double offset_z_m);

// The frame at axial distance s_m along the axis (x stays tangent to it).
Isometry fermi_frame(const Space& space, const Isometry& axis_frame, double s_m);

// A cue stick of given length whose chord is the x axis of `frame`, centred on
// the frame's origin, bowed toward the frame's +z by the signed sagitta
// (metres at the midpoint): h(u) = sagitta · (1 − (2u/L)²), u ∈ [−L/2, L/2].
struct BentStick {
  double length_m = 1.0;
  double sagitta_m = 0.0;
  double radius_m = 0.0125;

  // Offset from the chord at axial parameter u (metres from the midpoint).
  [[nodiscard]] double offset_m(double u_m) const;
  // The centre-line point at u.
  [[nodiscard]] Point centre_point(const Space& space, const Isometry& frame,
                                   double u_m) const;
  // A surface point at u, at angle phi around the centre line (phi = 0 toward
  // the frame's +y), using the chord's Fermi frame (exact for sagitta 0, and
  // within O(h'²) of the bent centre line's own normal otherwise).
  [[nodiscard]] Point surface_point(const Space& space, const Isometry& frame,
                                    double u_m, double phi_rad) const;
};

}  // namespace curvlab::geometry
