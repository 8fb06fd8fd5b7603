#include "curvlab/geometry/calibration.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

namespace curvlab::geometry {
namespace {

constexpr std::array<const char*, 4> kCornerNames = {"front-left", "front-right", "back-right",
                                                     "back-left"};

// Corner j of the unit-edge square with yaw 0, in (x, z): (−½, ½) turned by
// j quarter turns about +y, the same construction as table_edge_frame().
glm::dvec2 template_corner(int j) {
  const double turn = std::numbers::pi / 2.0 * j;
  const double c = std::cos(turn);
  const double s = std::sin(turn);
  const double x = -0.5;
  const double z = 0.5;
  // Rotation about +y acts on (x, z) as x' = x c + z s, z' = −x s + z c.
  return {x * c + z * s, -x * s + z * c};
}

glm::dvec2 rotate_about_y(const glm::dvec2& xz, double yaw_rad) {
  const double c = std::cos(yaw_rad);
  const double s = std::sin(yaw_rad);
  return {xz.x * c + xz.y * s, -xz.x * s + xz.y * c};
}

std::string mm(double metres) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  os << metres * 1000.0 << " mm";
  return os.str();
}

std::string touch_name(int j) {
  return "touch " + std::to_string(j + 1) + " (" + kCornerNames[static_cast<std::size_t>(j)] + ")";
}

constexpr const char* kOrderHint =
    "touch the corners in the order front-left, front-right, back-right, back-left as seen "
    "by the participant (counter-clockwise seen from above)";

}  // namespace

Vec3 physical_table_corner(const PhysicalTableFit& table, int j) {
  const glm::dvec2 xz = table.centre_m + rotate_about_y(template_corner(j) * table.edge_m,
                                                        table.yaw_rad);
  return {xz.x, table.height_m, xz.y};
}

std::variant<PhysicalTableFit, GeometryError> fit_square_table(std::span<const Vec3> corners_m,
                                                               const CalibrationLimits& limits) {
  const int n = static_cast<int>(corners_m.size());
  if (n != 3 && n != 4)
    return GeometryError{"table calibration needs 3 or 4 touched corners, got " +
                         std::to_string(n)};
  for (int j = 0; j < n; ++j) {
    const Vec3& p = corners_m[static_cast<std::size_t>(j)];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return GeometryError{touch_name(j) + " has a non-finite coordinate (lost tracking?)"};
  }

  // Orientation from the shoelace sum in (x, z). The yaw-0 template has a
  // negative sum, so a positive one means the corners went the other way
  // round; no rotation can fit a mirrored order, so say so plainly.
  double twice_area = 0.0;
  for (int j = 0; j < n; ++j) {
    const Vec3& a = corners_m[static_cast<std::size_t>(j)];
    const Vec3& b = corners_m[static_cast<std::size_t>((j + 1) % n)];
    twice_area += a.x * b.z - b.x * a.z;
  }
  const double template_twice_area = n == 4 ? -1.0 : -0.5;  // for unit edge
  const double min_edge2 = limits.min_edge_m * limits.min_edge_m;
  if (twice_area > 0.25 * min_edge2 * -template_twice_area)
    return GeometryError{std::string("the corners were touched clockwise seen from above; ") +
                         kOrderHint};

  // Similarity Procrustes in the floor plane: with centred template q' and
  // centred touches p', the yaw maximising Σ p'·R q' is atan2(B, A) with
  // A = Σ p'·q', B = Σ (p'x q'z − p'z q'x), and the scale is √(A²+B²)/Σ|q'|².
  glm::dvec2 q_mean{0.0};
  glm::dvec2 p_mean{0.0};
  double height_sum = 0.0;
  for (int j = 0; j < n; ++j) {
    const Vec3& p = corners_m[static_cast<std::size_t>(j)];
    q_mean += template_corner(j);
    p_mean += glm::dvec2(p.x, p.z);
    height_sum += p.y;
  }
  q_mean /= static_cast<double>(n);
  p_mean /= static_cast<double>(n);
  double a = 0.0;
  double b = 0.0;
  double q_norm2 = 0.0;
  for (int j = 0; j < n; ++j) {
    const Vec3& p = corners_m[static_cast<std::size_t>(j)];
    const glm::dvec2 qc = template_corner(j) - q_mean;
    const glm::dvec2 pc = glm::dvec2(p.x, p.z) - p_mean;
    a += pc.x * qc.x + pc.y * qc.y;
    b += pc.x * qc.y - pc.y * qc.x;
    q_norm2 += qc.x * qc.x + qc.y * qc.y;
  }

  PhysicalTableFit fit;
  fit.corners_used = n;
  fit.yaw_rad = std::atan2(b, a);
  fit.fitted_edge_m = std::hypot(a, b) / q_norm2;
  // With the edge known, the rigid fit keeps the same yaw (it maximises the
  // same sum) at the known scale.
  fit.edge_m = limits.known_edge_m ? *limits.known_edge_m : fit.fitted_edge_m;
  fit.centre_m = p_mean - rotate_about_y(q_mean * fit.edge_m, fit.yaw_rad);
  fit.height_m = height_sum / n;

  double sum2 = 0.0;
  for (int j = 0; j < n; ++j) {
    const double r = glm::length(corners_m[static_cast<std::size_t>(j)] -
                                 physical_table_corner(fit, j));
    sum2 += r * r;
    fit.corner_residual_m[static_cast<std::size_t>(j)] = r;
    if (r > fit.max_residual_m) {
      fit.max_residual_m = r;
      fit.worst_corner = j;
    }
  }
  fit.rms_residual_m = std::sqrt(sum2 / n);

  if (fit.fitted_edge_m < limits.min_edge_m || fit.fitted_edge_m > limits.max_edge_m)
    return GeometryError{"the fitted table edge is " + mm(fit.fitted_edge_m) + ", outside " +
                         mm(limits.min_edge_m) + " … " + mm(limits.max_edge_m) +
                         " (were two touches made at the same corner?)"};
  // A table of another size first: its touches would also miss the known
  // corners, but the edge says why.
  if (limits.known_edge_m && !(std::abs(fit.fitted_edge_m - *limits.known_edge_m) <= limits.max_edge_difference_m))
    return GeometryError{"the touches span a table of edge " + mm(fit.fitted_edge_m) + ", the table as known has " +
                         mm(*limits.known_edge_m) + " (the protocol's [table] edge_m or --edge-m): they differ by " +
                         mm(std::abs(fit.fitted_edge_m - *limits.known_edge_m)) + ", more than the " +
                         mm(limits.max_edge_difference_m) +
                         " tolerance: measure the table and give its edge (--edge-m, or the protocol's [table] "
                         "edge_m), or touch the corners again"};
  if (!(fit.max_residual_m <= limits.max_residual_m))
    return GeometryError{"the touches do not form a square table: " +
                         touch_name(fit.worst_corner) + " is " + mm(fit.max_residual_m) +
                         " from the fitted corner (limit " + mm(limits.max_residual_m) +
                         "); repeat the calibration and " + kOrderHint};
  return fit;
}

std::vector<Vec3> simulate_corner_touches(const PhysicalTableFit& truth, int corner_count,
                                          double noise_sd_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  // normal_distribution needs a positive deviation; zero means exact touches.
  std::normal_distribution<double> noise(0.0, noise_sd_m > 0.0 ? noise_sd_m : 1.0);
  const double gain = noise_sd_m > 0.0 ? 1.0 : 0.0;
  std::vector<Vec3> out;
  for (int j = 0; j < corner_count; ++j) {
    const Vec3 c = physical_table_corner(truth, j % 4);
    const double dx = noise(rng);
    const double dy = noise(rng);
    const double dz = noise(rng);
    out.push_back(c + gain * Vec3(dx, dy, dz));
  }
  return out;
}

}  // namespace curvlab::geometry
