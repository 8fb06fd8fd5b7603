#include "curvlab/renderer/view.hpp"

#include "curvlab/geometry/maps.hpp"

#include <glm/geometric.hpp>
#include <glm/mat3x3.hpp>

#include <cmath>
#include <cstdlib>
#include <numbers>

namespace curvlab::renderer {

using geometry::SpaceKind;

ViewSettings ViewSettings::preset(ViewPreset preset) {
  ViewSettings s;
  const PresetViewing viewing = preset_viewing(preset);
  s.projection = viewing.projection;
  s.eyes = viewing.eyes;
  return s;
}

bool ViewSettings::shows(Eye eye) const {
  switch (eyes) {
    case EyeSelection::both: return true;
    case EyeSelection::left: return eye == Eye::left;
    case EyeSelection::right: return eye == Eye::right;
    case EyeSelection::dominant: return eye == dominant_eye;
  }
  return true;
}

Fov Fov::symmetric(double horizontal_rad, double aspect_w_over_h) {
  const double tx = std::tan(horizontal_rad / 2.0);
  const double ty = tx / aspect_w_over_h;
  const double vertical = std::atan(ty);
  return {-horizontal_rad / 2.0, horizontal_rad / 2.0, vertical, -vertical};
}

StereoRig StereoRig::from_ipd(double ipd_m, const Fov& fov) {
  StereoRig rig;
  rig.eyes[0] = {{-ipd_m / 2.0, 0.0, 0.0}, glm::dmat3(1.0), fov};
  rig.eyes[1] = {{ipd_m / 2.0, 0.0, 0.0}, glm::dmat3(1.0), fov};
  return rig;
}

double projective_depth(const Space& space, double t_rad) {
  return space.C(t_rad) / space.S(t_rad);
}

glm::dmat4 projection_matrix(const Fov& fov, double c_near, double c_far, double depth_lo,
                             double depth_hi) {
  const double l = std::tan(fov.angle_left_rad);
  const double r = std::tan(fov.angle_right_rad);
  const double u = std::tan(fov.angle_up_rad);
  const double d = std::tan(fov.angle_down_rad);
  const double b = (depth_hi - depth_lo) / (c_far - c_near);
  const double a = depth_lo - b * c_near;
  glm::dmat4 m(0.0);
  // Rows: clip.x = (2x + (r+l)z)/(r−l); clip.y = −(2y + (u+d)z)/(u−d)
  // (Vulkan's y points down); clip.z = a(−z) + b·w; clip.w = −z.
  m[0][0] = 2.0 / (r - l);
  m[2][0] = (r + l) / (r - l);
  m[1][1] = -2.0 / (u - d);
  m[2][1] = -(u + d) / (u - d);
  m[2][2] = -a;
  m[3][2] = b;
  m[2][3] = -1.0;
  return m;
}

ViewConstants make_view_constants(const Space& space, const ViewSettings& settings,
                                  const Isometry& head, const EyeOffset& eye) {
  ViewConstants v;
  v.projection = settings.projection;
  v.space = space;
  v.fov = eye.fov;
  // S3 splits the depth range: front hemisphere in [0, ½], back in [½, 1]
  // (paper, "The 3-sphere", technical detail).
  const bool split = space.kind == SpaceKind::S3;
  const double front_hi = split ? 0.5 : 1.0;
  switch (settings.projection) {
    case Projection::tourist: {
      const double c_near = projective_depth(space, settings.near_m / space.radius_m);
      // The far limit of w/(−z): E3 0, S3 −c_near (distance π − ε), H3 1.
      const double c_far = space.kind == SpaceKind::E3 ? 0.0
                           : space.kind == SpaceKind::S3 ? -c_near
                                                         : 1.0;
      v.proj_front = projection_matrix(eye.fov, c_near, c_far, 0.0, front_hi);
      v.proj_back = projection_matrix(eye.fov, c_near, c_far, 0.5, 1.0);
      const Isometry eye_pose = head * geometry::translation_m(space, eye.position_m) *
                                geometry::rotation(eye.rotation);
      v.viewer_from_world = geometry::inverse(space, eye_pose);
      break;
    }
    case Projection::native: {
      // Euclidean projection of (e, 1 m): w/(−z) = 1/distance, far limit 0.
      const double c_near = 1.0 / settings.near_m;
      v.proj_front = projection_matrix(eye.fov, c_near, 0.0, 0.0, front_hi);
      v.proj_back = projection_matrix(eye.fov, c_near, 0.0, 0.5, 1.0);
      const glm::dmat3 rt = glm::transpose(eye.rotation);
      const glm::dvec3 t = -(rt * eye.position_m);
      glm::dmat4 m(1.0);
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) m[c][r] = rt[c][r];
      m[3] = glm::dvec4(t, 1.0);
      v.eye_from_nose = m;
      v.viewer_from_world = geometry::inverse(space, head);
      break;
    }
  }
  return v;
}

glm::dvec4 clip_position(const ViewConstants& view, Hemisphere hemi, const Point& p) {
  const glm::dmat4& proj = hemi == Hemisphere::back ? view.proj_back : view.proj_front;
  switch (view.projection) {
    case Projection::tourist: return proj * (hemi == Hemisphere::back ? -p : p);
    case Projection::native: {
      const geometry::Vec3 q = hemi == Hemisphere::back ? geometry::back_log_origin(view.space, p)
                                                        : geometry::log_origin(view.space, p);
      return proj * (view.eye_from_nose * glm::dvec4(q, 1.0));
    }
  }
  std::abort();  // not a Projection: a broken contract
}

std::optional<glm::dvec2> to_pixels(const glm::dvec4& clip, double width_px, double height_px) {
  if (!(clip.w > 0.0)) return std::nullopt;
  return glm::dvec2((clip.x / clip.w * 0.5 + 0.5) * width_px,
                    (clip.y / clip.w * 0.5 + 0.5) * height_px);
}

namespace {

double distance_to_segment(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b) {
  const glm::dvec2 ab = b - a;
  const double len2 = glm::dot(ab, ab);
  const double f = len2 > 0.0 ? std::clamp(glm::dot(p - a, ab) / len2, 0.0, 1.0) : 0.0;
  return glm::length(p - (a + f * ab));
}

}  // namespace

EdgeError edge_screen_error(const ViewConstants& view, Hemisphere hemi,
                            const glm::dmat4& model_view, const GeodesicEdge& edge, int segments,
                            double width_px, double height_px, int samples_per_segment) {
  const Space& space = view.space;
  const Point a = model_view * edge.a;
  const Point b = model_view * edge.b;
  // The geodesic through a and b: p(f) = (S((1−f)d)·a + S(f·d)·b) / S(d),
  // one formula for all three spaces (linear interpolation in E3).
  const double d_rad = geometry::distance_rad(space, a, b);
  const double s_d = space.S(d_rad);
  auto curve = [&](double f) {
    const Point p = s_d > 1e-12 ? (space.S((1.0 - f) * d_rad) * a + space.S(f * d_rad) * b) / s_d
                                : (1.0 - f) * a + f * b;
    return to_pixels(clip_position(view, hemi, p), width_px, height_px);
  };
  EdgeError err;
  double sum = 0.0;
  std::optional<glm::dvec2> start = curve(0.0);
  for (int i = 0; i < segments; ++i) {
    const std::optional<glm::dvec2> end = curve(static_cast<double>(i + 1) / segments);
    if (start && end) {
      for (int s = 1; s < samples_per_segment; ++s) {
        const double f = (i + static_cast<double>(s) / samples_per_segment) / segments;
        const auto p = curve(f);
        if (!p) continue;
        const double d = distance_to_segment(*p, *start, *end);
        err.max_px = std::max(err.max_px, d);
        sum += d;
        ++err.samples;
      }
    }
    start = end;
  }
  err.mean_px = err.samples > 0 ? sum / err.samples : 0.0;
  return err;
}

}  // namespace curvlab::renderer
