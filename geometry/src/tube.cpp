#include "curvlab/geometry/tube.hpp"

#include "curvlab/geometry/maps.hpp"

#include <cmath>

namespace curvlab::geometry {

Isometry fermi_frame(const Space& space, const Isometry& axis_frame, double s_m) {
  return axis_frame *
         translation_rad(space, Vec3(1.0, 0.0, 0.0), s_m / space.radius_m);
}

Point fermi_point(const Space& space, const Isometry& axis_frame, double s_m,
                  double offset_y_m, double offset_z_m) {
  return fermi_frame(space, axis_frame, s_m) *
         exp_origin(space, Vec3(0.0, offset_y_m, offset_z_m));
}

double BentStick::offset_m(double u_m) const {
  const double f = 2.0 * u_m / length_m;
  return sagitta_m * (1.0 - f * f);
}

Point BentStick::centre_point(const Space& space, const Isometry& frame,
                              double u_m) const {
  return fermi_point(space, frame, u_m, 0.0, offset_m(u_m));
}

Point BentStick::surface_point(const Space& space, const Isometry& frame, double u_m,
                               double phi_rad) const {
  return fermi_point(space, frame, u_m, radius_m * std::cos(phi_rad),
                     offset_m(u_m) + radius_m * std::sin(phi_rad));
}

}  // namespace curvlab::geometry
