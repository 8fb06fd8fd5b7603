// The regular honeycombs {p,3,q} that tile each space with its natural cell
// (DESIGN.md §4): {5,3,3} (the 120-cell) in S3, {4,3,4} (cubes) in E3,
// {5,3,4} (right-angled dodecahedra) in H3. Built by reflecting one cell in
// its faces; one code path for all three spaces through the forms P and g.
#pragma once

#include "curvlab/renderer/mesh.hpp"

namespace curvlab::renderer {

struct TilingOptions {
  double reach_rad = 3.0;     // cells whose centre lies within this distance (H3)
  double reach_e3_m = 3.2;    // the same in E3, metres
  double cube_edge_e3_m = 1.0;
  std::size_t max_cells = 400;
};

struct Tiling {
  int p = 5;  // faces are p-gons
  int q = 3;  // q cells around each edge
  double cell_circumradius_rad = 0.0;
  std::size_t cells = 0;
  std::vector<GeodesicEdge> edges;  // unique, in world (= model) coordinates
};

// The honeycomb of the space, centred on the origin (a cell centre).
Tiling build_tiling(const Space& space, const TilingOptions& options = {});

// Dihedral angle of the regular {p,3} polyhedron with circumradius R (radians
// of the space; in E3 any R gives the Euclidean angle).
double regular_cell_dihedral_rad(const Space& space, int p, double circumradius_rad);

// Splits the edges into shells by the distance of their midpoints from the
// origin, so each shell gets its own subdivision level (near edges bend
// most in the native view).
std::vector<Tiling> split_into_shells(const Space& space, const Tiling& tiling, int shells);

// The edges as a line mesh, each split into 2^level geodesic pieces, coloured
// from light (near the origin) to dim (far).
MeshData build_tiling_mesh(const Space& space, const Tiling& tiling, int level);
MeshInfo tiling_info(const Space& space, const Tiling& tiling);

}  // namespace curvlab::renderer
