#include "curvlab/renderer/plan.hpp"

#include "curvlab/geometry/maps.hpp"

#include <glm/geometric.hpp>

#include <cmath>
#include <cstdlib>
#include <numbers>

namespace curvlab::renderer {

using geometry::SpaceKind;

int RenderPlan::rendered_views() const {
  int n = 0;
  for (const auto& v : views) n += v.rendered ? 1 : 0;
  return n;
}

std::size_t RenderPlan::draw_count() const {
  std::size_t n = 0;
  for (const auto& v : views) n += v.draws.size();
  return n;
}

namespace {

// Inward unit normals of the four side planes of an eye's frustum, in the
// eye's axes (x right, y up, −z forward).
std::array<glm::dvec3, 4> side_normals(const Fov& fov) {
  auto inward = [](double angle, const glm::dvec3& axis_pos, double sign) {
    // Plane containing the view direction rotated by `angle` toward axis_pos;
    // its inward normal points back toward the axis.
    const glm::dvec3 dir = std::cos(angle) * glm::dvec3(0, 0, -1) + std::sin(angle) * axis_pos;
    const glm::dvec3 n = glm::normalize(glm::cross(dir, glm::cross(axis_pos, glm::dvec3(0, 0, -1))));
    return sign * n;
  };
  std::array<glm::dvec3, 4> n{inward(fov.angle_left_rad, {1, 0, 0}, 1.0),
                              inward(fov.angle_right_rad, {1, 0, 0}, -1.0),
                              inward(fov.angle_up_rad, {0, 1, 0}, -1.0),
                              inward(fov.angle_down_rad, {0, 1, 0}, 1.0)};
  return n;
}

// The side planes of the frustum are planes through the eye: the signed
// distance to one with unit normal n is S(d) = n·xyz/ρ, and a ball is inside
// when d ≥ −r for every side plane.
bool tourist_may_be_visible(const ViewConstants& view, Hemisphere hemi, const Point& centre, double radius_m) {
  const Space& s = view.space;
  const Point c = hemi == Hemisphere::back ? -centre : centre;
  const double r_rad = radius_m / s.radius_m;
  const double limit = s.kind == SpaceKind::S3 && r_rad >= std::numbers::pi / 2.0 ? -1.0 : -s.S(r_rad);
  for (const auto& n : side_normals(view.fov))
    if (glm::dot(n, glm::dvec3(c)) / s.radius_m < limit) return false;
  return true;
}

// The map keeps directions from the nose and sets distance to the geodesic
// distance, so a ball of radius r at distance θ lands in the cone of
// half-angle α, sin α = S(r)/S(θ), about the centre's direction, between
// ρ(θ−r) and ρ(θ+r) — or, seen through the S3 antipode, about the opposite
// direction between ρ(2π−θ−r) and ρ(2π−θ+r). That cone section is held by a
// ball about the centre's image; the eye's few centimetres of offset are
// inside the frustum test's margin.
bool native_may_be_visible(const ViewConstants& view, Hemisphere hemi, const Point& centre, double radius_m) {
  const Space& s = view.space;
  const double theta = geometry::distance_from_origin_rad(s, centre);
  const double r_rad = radius_m / s.radius_m;
  if (r_rad >= theta) return true;  // the ball holds the nose: any direction
  if (s.kind == SpaceKind::S3 && theta + r_rad >= std::numbers::pi) return true;
  const double sin_alpha = std::min(1.0, s.S(r_rad) / s.S(theta));
  const geometry::Vec3 q = hemi == Hemisphere::back ? geometry::back_log_origin(s, centre)
                                                    : geometry::log_origin(s, centre);
  const double far_m = s.radius_m * ((hemi == Hemisphere::back ? 2.0 * std::numbers::pi - theta : theta) + r_rad);
  const double r = std::hypot(radius_m, far_m * sin_alpha) + 0.05;
  const glm::dvec3 e = glm::dvec3(view.eye_from_nose * glm::dvec4(q, 1.0));
  for (const auto& n : side_normals(view.fov))
    if (glm::dot(n, e) < -r) return false;
  return true;
}

// Whether the projection draws a geodesic as a curve, so that long edges
// need subdividing: the log map bends them; true optics keeps them straight.
bool bends_geodesics(Projection projection) {
  switch (projection) {
    case Projection::tourist: return false;
    case Projection::native: return true;
  }
  std::abort();  // not a Projection: a broken contract
}

}  // namespace

bool may_be_visible(const ViewConstants& view, Hemisphere hemi, const Point& centre,
                    double radius_m) {
  if (radius_m >= 1e29) return true;
  switch (view.projection) {
    case Projection::tourist: return tourist_may_be_visible(view, hemi, centre, radius_m);
    case Projection::native: return native_may_be_visible(view, hemi, centre, radius_m);
  }
  std::abort();  // not a Projection: a broken contract
}

std::pair<int, double> choose_level(const ViewConstants& view, Hemisphere hemi,
                                    const glm::dmat4& model_view, const MeshInfo& info,
                                    const FrameDescription& frame) {
  if (!bends_geodesics(view.projection) || info.long_edges.empty()) return {0, 0.0};
  if (frame.settings.forced_level) {
    double err = 0.0;
    for (const auto& edge : info.long_edges)
      err = std::max(err, edge_screen_error(view, hemi, model_view, edge,
                                            info.base_segments << *frame.settings.forced_level,
                                            frame.width_px, frame.height_px, 4)
                              .max_px);
    return {*frame.settings.forced_level, err};
  }
  auto error_at = [&](int level) {
    double err = 0.0;
    for (const auto& edge : info.long_edges)
      err = std::max(err, edge_screen_error(view, hemi, model_view, edge,
                                            info.base_segments << level, frame.width_px,
                                            frame.height_px, 4)
                              .max_px);
    return err;
  };
  // The chord error of a smooth curve falls as 1/pieces², a quarter per
  // level: predict the level from level 0, then verify (and step up if the
  // prediction was short).
  const double budget = frame.settings.error_budget_px;
  const double err0 = error_at(0);
  if (err0 <= budget) return {0, err0};
  int level = std::clamp(static_cast<int>(std::ceil(std::log(err0 / budget) / std::log(4.0))), 1,
                         kMaxSubdivisionLevel);
  double err = error_at(level);
  while (err > budget && level < kMaxSubdivisionLevel) err = error_at(++level);
  return {level, err};
}

glm::dmat4 head_locked_clip(const EyeOffset& eye, const glm::dmat4& nose_from_model) {
  const glm::dmat3 rt = glm::transpose(eye.rotation);
  glm::dmat4 eye_from_nose(rt);
  eye_from_nose[3] = glm::dvec4(-(rt * eye.position_m), 1.0);
  // Euclidean points (x, y, z, 1): w/(−z) is 1/distance, 20 at 5 cm, 0.01 at 100 m.
  return projection_matrix(eye.fov, 1.0 / 0.05, 1.0 / 100.0, 0.0, 1.0) * eye_from_nose * nose_from_model;
}

RenderPlan plan_frame(const Scene& scene, const FrameDescription& frame) {
  RenderPlan plan;
  const bool s3 = frame.space.kind == SpaceKind::S3;
  const bool back_allowed = s3 && frame.settings.back_hemisphere;
  for (int e = 0; e < 2; ++e) {
    ViewPlan& vp = plan.views[e];
    vp.eye = static_cast<Eye>(e);
    vp.rendered = frame.settings.shows(vp.eye);
    if (!vp.rendered) continue;
    vp.constants = make_view_constants(frame.space, frame.settings, frame.head, frame.rig.eyes[e]);
    const auto& objects = scene.objects();
    for (int h = 0; h < (back_allowed ? 2 : 1); ++h) {
      const auto hemi = static_cast<Hemisphere>(h);
      for (std::size_t i = 0; i < objects.size(); ++i) {
        const SceneObject& o = objects[i];
        if (!o.visible) continue;
        if (o.head_locked) {
          if (hemi == Hemisphere::front && frame.draw_head_locked)
            vp.draws.push_back({i, 0, hemi, head_locked_clip(frame.rig.eyes[e], o.pose.m), true});
          continue;
        }
        const glm::dmat4 mv = vp.constants.viewer_from_world.m * o.pose.m;
        bool visible = o.info.bounds.empty();
        for (const auto& ball : o.info.bounds)
          visible = visible || may_be_visible(vp.constants, hemi, mv * ball.centre, ball.radius_m);
        if (!visible) {
          ++vp.culled;
          continue;
        }
        const auto [level, err] = choose_level(vp.constants, hemi, mv, o.info, frame);
        vp.estimated_error_px = std::max(vp.estimated_error_px, err);
        plan.max_level = std::max(plan.max_level, level);
        vp.draws.push_back({i, level, hemi, mv});
        if (hemi == Hemisphere::back) plan.back_hemisphere = true;
      }
    }
  }
  return plan;
}

}  // namespace curvlab::renderer
