// Right-angled regular n-gon billiards tables (paper, "Construction of the
// billiards tables"): every corner 90°, every edge as long as the physical
// table's. S3 admits only the triangle, E3 only the square, H3 any n ≥ 5.
//
// For a regular n-gon with interior angle α: C(s/2) = cos(π/n) / sin(α/2).
// With α = 90°: C(s/2) = √2·cos(π/n). When the edge must match a physical
// length L, ρ = L / s.
#pragma once

#include "curvlab/geometry/isometry.hpp"

#include <string>
#include <variant>
#include <vector>

namespace curvlab::geometry {

struct TableShape {
  int sides = 4;
  double side_rad = 0.0;        // edge length in radians of the space
  double radius_m = 1.0;        // ρ
  double edge_m = 0.0;          // edge length in metres (side_rad · ρ)
  double interior_angle_rad = 0.0;
  double circumradius_rad = 0.0;  // centre to corner
  double apothem_rad = 0.0;       // centre to edge midpoint
  // n/4: laps of the square physical table per lap of this virtual table.
  [[nodiscard]] double physical_laps_per_virtual_lap() const { return sides / 4.0; }
  [[nodiscard]] double circumradius_m() const { return circumradius_rad * radius_m; }
  [[nodiscard]] double apothem_m() const { return apothem_rad * radius_m; }
};

// The default number of sides per space: 3, 4, 5.
int default_table_sides(SpaceKind kind);

// An error a person can act on (bad argument values, impossible tables).
struct GeometryError {
  std::string message;
};

// The right-angled table whose edge is edge_m metres. In S3 and H3 this fixes
// ρ = edge_m / side_rad; in E3 the side in radians follows from e3_radius_m.
std::variant<TableShape, GeometryError> right_angled_table_from_edge(
    SpaceKind kind, double edge_m, int sides, double e3_radius_m = 1.0);

// The right-angled table in a space of given radius (edge = side_rad · ρ);
// in E3 the square's edge is free, so edge_m is required there.
std::variant<TableShape, GeometryError> right_angled_table_from_radius(
    const Space& space, int sides, double e3_edge_m = 0.9);

// Corner j of the table centred at the origin in the horizontal plane y = 0.
// Edges run counter-clockwise seen from above (+y); edge j joins corner j to
// corner j+1 and edge 0 faces +z (the default participant side).
Point table_corner(const Space& space, const TableShape& table, int j);

// A frame on edge j at along_m metres from its first corner: x along the edge
// (counter-clockwise), y up, z outward (away from the centre).
Isometry table_edge_frame(const Space& space, const TableShape& table, int edge,
                          double along_m);

}  // namespace curvlab::geometry
