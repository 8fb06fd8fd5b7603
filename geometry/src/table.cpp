#include "curvlab/geometry/table.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

namespace curvlab::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

bool sides_allowed(SpaceKind kind, int n) {
  switch (kind) {
    case SpaceKind::S3: return n == 3;
    case SpaceKind::E3: return n == 4;
    case SpaceKind::H3: return n >= 5;
  }
  return false;
}

std::string sides_expectation(SpaceKind kind) {
  switch (kind) {
    case SpaceKind::S3: return "3 (only a triangle has 90° corners in S3)";
    case SpaceKind::E3: return "4 (only a square has 90° corners in E3)";
    case SpaceKind::H3: return "5 or more (an n-gon with 90° corners in H3 needs n ≥ 5)";
  }
  return "?";
}

// Fills side, angle, circumradius and apothem (all in radians) for a space
// whose radius is already known.
TableShape shape_in(const Space& space, int n, double side_rad) {
  TableShape t;
  t.sides = n;
  t.side_rad = side_rad;
  t.radius_m = space.radius_m;
  t.edge_m = side_rad * space.radius_m;
  t.interior_angle_rad = kPi / 2.0;
  const double half = side_rad / 2.0;
  // Right triangle centre–midpoint–corner, angle π/n at the centre:
  //   S(s/2) = S(R)·sin(π/n)        (sine rule)
  //   S(a)   = T(s/2) / tan(π/n)    (T = S/C; a = apothem; the angle at
  //                                  the centre has tan = T(opposite)/S(adjacent))
  t.circumradius_rad = space.S_inv(space.S(half) / std::sin(kPi / n));
  if (space.kind == SpaceKind::S3 && space.S(half) / std::sin(kPi / n) >= 1.0)
    t.circumradius_rad = kPi / 2.0;
  t.apothem_rad = space.S_inv((space.S(half) / space.C(half)) / std::tan(kPi / n));
  return t;
}

// The side in radians of the right-angled regular n-gon: C(s/2) = √2 cos(π/n).
double right_angled_side_rad(const Space& space, int n) {
  return 2.0 * space.C_inv(std::sqrt(2.0) * std::cos(kPi / n));
}

}  // namespace

int default_table_sides(SpaceKind kind) {
  switch (kind) {
    case SpaceKind::S3: return 3;
    case SpaceKind::E3: return 4;
    case SpaceKind::H3: return 5;
  }
  return 4;
}

std::variant<TableShape, GeometryError> right_angled_table_from_edge(
    SpaceKind kind, double edge_m, int sides, double e3_radius_m) {
  if (!(edge_m > 0.0) || !std::isfinite(edge_m))
    return GeometryError{"edge length must be a positive number of metres"};
  if (!sides_allowed(kind, sides)) {
    std::ostringstream os;
    os << "a right-angled regular table in " << to_string(kind) << " has "
       << sides_expectation(kind) << " sides, not " << sides;
    return GeometryError{os.str()};
  }
  if (kind == SpaceKind::E3) {
    if (!(e3_radius_m > 0.0) || !std::isfinite(e3_radius_m))
      return GeometryError{"radius must be a positive number of metres"};
    const Space space{kind, e3_radius_m};
    return shape_in(space, sides, edge_m / e3_radius_m);
  }
  const Space unit{kind, 1.0};
  const double side = right_angled_side_rad(unit, sides);
  const Space space{kind, edge_m / side};
  return shape_in(space, sides, side);
}

std::variant<TableShape, GeometryError> right_angled_table_from_radius(
    const Space& space, int sides, double e3_edge_m) {
  if (!(space.radius_m > 0.0) || !std::isfinite(space.radius_m))
    return GeometryError{"radius must be a positive number of metres"};
  if (space.kind == SpaceKind::E3)
    return right_angled_table_from_edge(space.kind, e3_edge_m, sides, space.radius_m);
  if (!sides_allowed(space.kind, sides))
    return right_angled_table_from_edge(space.kind, 1.0, sides);  // same message
  return shape_in(space, sides, right_angled_side_rad(space, sides));
}

Point table_corner(const Space& space, const TableShape& table, int j) {
  return position(space, table_edge_frame(space, table, j, 0.0));
}

Isometry table_edge_frame(const Space& space, const TableShape& table, int edge,
                          double along_m) {
  const int n = table.sides;
  const int e = ((edge % n) + n) % n;
  const double turn = 2.0 * kPi * e / n;
  return rotation(Vec3(0.0, 1.0, 0.0), turn) *
         translation_rad(space, Vec3(0.0, 0.0, 1.0), table.apothem_rad) *
         translation_rad(space, Vec3(1.0, 0.0, 0.0),
                         along_m / space.radius_m - table.side_rad / 2.0);
}

}  // namespace curvlab::geometry
