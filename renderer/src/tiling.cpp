#include "curvlab/renderer/tiling.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/renderer/colour.hpp"

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <map>
#include <numbers>
#include <tuple>

namespace curvlab::renderer {

using geometry::SpaceKind;
using geometry::Vec3;
using geometry::Vec4;

namespace {

struct Cell {
  std::vector<Vec3> vertex_dirs;           // unit directions from the centre
  std::vector<std::vector<int>> faces;     // vertex indices (3 used per face)
  std::vector<std::pair<int, int>> edges;
};

Cell regular_cell(int p) {
  Cell c;
  std::vector<Vec3> face_dirs;
  if (p == 4) {
    for (int i = 0; i < 8; ++i)
      c.vertex_dirs.push_back(glm::normalize(
          Vec3(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0)));
    for (int a = 0; a < 3; ++a)
      for (double s : {-1.0, 1.0}) {
        Vec3 n(0.0);
        n[a] = s;
        face_dirs.push_back(n);
      }
  } else {
    const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
    for (int i = 0; i < 8; ++i)
      c.vertex_dirs.push_back(glm::normalize(
          Vec3(i & 1 ? 1.0 : -1.0, i & 2 ? 1.0 : -1.0, i & 4 ? 1.0 : -1.0)));
    for (double s1 : {-1.0, 1.0})
      for (double s2 : {-1.0, 1.0}) {
        c.vertex_dirs.push_back(glm::normalize(Vec3(0.0, s1 / phi, s2 * phi)));
        c.vertex_dirs.push_back(glm::normalize(Vec3(s1 / phi, s2 * phi, 0.0)));
        c.vertex_dirs.push_back(glm::normalize(Vec3(s1 * phi, 0.0, s2 / phi)));
        face_dirs.push_back(glm::normalize(Vec3(0.0, s1, s2 * phi)));
        face_dirs.push_back(glm::normalize(Vec3(s1, s2 * phi, 0.0)));
        face_dirs.push_back(glm::normalize(Vec3(s1 * phi, 0.0, s2)));
      }
  }
  // A face holds the p vertices nearest its centre direction.
  for (const Vec3& n : face_dirs) {
    std::vector<std::pair<double, int>> by_dot;
    for (int i = 0; i < static_cast<int>(c.vertex_dirs.size()); ++i)
      by_dot.emplace_back(-glm::dot(c.vertex_dirs[i], n), i);
    std::sort(by_dot.begin(), by_dot.end());
    std::vector<int> face;
    for (int i = 0; i < p; ++i) face.push_back(by_dot[i].second);
    c.faces.push_back(face);
  }
  double shortest = 1e9;
  for (std::size_t i = 0; i < c.vertex_dirs.size(); ++i)
    for (std::size_t j = i + 1; j < c.vertex_dirs.size(); ++j)
      shortest = std::min(shortest, glm::length(c.vertex_dirs[i] - c.vertex_dirs[j]));
  for (int i = 0; i < static_cast<int>(c.vertex_dirs.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(c.vertex_dirs.size()); ++j)
      if (glm::length(c.vertex_dirs[i] - c.vertex_dirs[j]) < shortest * 1.01)
        c.edges.emplace_back(i, j);
  return c;
}

// The covector f with f(a) = f(b) = f(c) = 0 (generalised cross product).
Vec4 cross4(const Vec4& a, const Vec4& b, const Vec4& c) {
  auto det3 = [](double a0, double a1, double a2, double b0, double b1, double b2, double c0,
                 double c1, double c2) {
    return a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0);
  };
  return {det3(a.y, a.z, a.w, b.y, b.z, b.w, c.y, c.z, c.w),
          -det3(a.x, a.z, a.w, b.x, b.z, b.w, c.x, c.z, c.w),
          det3(a.x, a.y, a.w, b.x, b.y, b.w, c.x, c.y, c.w),
          -det3(a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z)};
}

// The plane covector of a face, oriented so the cell centre is on its
// negative side, and its "raised" normal ñ = (f_xyz, k f_w).
struct FacePlane {
  Vec4 f;
  Vec4 n;
};

std::vector<FacePlane> face_planes(const Space& space, const Cell& cell, double R,
                                   std::vector<Point>* vertices) {
  std::vector<Point> v;
  for (const Vec3& d : cell.vertex_dirs)
    v.push_back(geometry::exp_origin(space, d * (R * space.radius_m)));
  std::vector<FacePlane> planes;
  const Point o = geometry::origin(space);
  for (const auto& face : cell.faces) {
    Vec4 f = cross4(v[face[0]], v[face[1]], v[face[2]]);
    if (glm::dot(f, o) > 0.0) f = -f;
    planes.push_back({f, Vec4(f.x, f.y, f.z, space.k() * f.w)});
  }
  if (vertices != nullptr) *vertices = v;
  return planes;
}

double form(const FacePlane& a, const FacePlane& b) { return glm::dot(a.f, b.n); }

glm::dmat4 reflection(const FacePlane& plane) {
  // x ↦ x − 2 f(x)/f(ñ) · ñ
  const double s = 2.0 / glm::dot(plane.f, plane.n);
  glm::dmat4 m(1.0);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m[c][r] -= s * plane.n[r] * plane.f[c];
  return m;
}

}  // namespace

double regular_cell_dihedral_rad(const Space& space, int p, double circumradius_rad) {
  const Cell cell = regular_cell(p);
  const auto planes = face_planes(space, cell, circumradius_rad, nullptr);
  // Two faces sharing an edge: the pair with the largest |form|... pick the
  // faces sharing two vertices.
  for (std::size_t i = 1; i < cell.faces.size(); ++i) {
    int shared = 0;
    for (int a : cell.faces[0])
      for (int b : cell.faces[i]) shared += a == b;
    if (shared == 2) {
      const double c = -form(planes[0], planes[i]) /
                       std::sqrt(form(planes[0], planes[0]) * form(planes[i], planes[i]));
      return std::acos(std::clamp(c, -1.0, 1.0));
    }
  }
  return 0.0;
}

Tiling build_tiling(const Space& space, const TilingOptions& options) {
  Tiling t;
  t.p = space.kind == SpaceKind::E3 ? 4 : 5;
  t.q = space.kind == SpaceKind::S3 ? 3 : 4;
  const double target = 2.0 * std::numbers::pi / t.q;
  double R = 0.0;
  if (space.kind == SpaceKind::E3) {
    R = options.cube_edge_e3_m * std::sqrt(3.0) / 2.0 / space.radius_m;
  } else {
    // Bisection: the dihedral grows with R in S3 and shrinks in H3.
    double lo = 1e-4;
    double hi = space.kind == SpaceKind::S3 ? 1.5 : 4.0;
    const double sign = space.kind == SpaceKind::S3 ? 1.0 : -1.0;
    for (int i = 0; i < 100; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (sign * (regular_cell_dihedral_rad(space, t.p, mid) - target) < 0.0)
        lo = mid;
      else
        hi = mid;
    }
    R = 0.5 * (lo + hi);
  }
  t.cell_circumradius_rad = R;
  const Cell cell = regular_cell(t.p);
  std::vector<Point> verts;
  const auto planes = face_planes(space, cell, R, &verts);
  std::vector<glm::dmat4> mirrors;
  for (const auto& pl : planes) mirrors.push_back(reflection(pl));

  const Point o = geometry::origin(space);
  const double reach = space.kind == SpaceKind::E3 ? options.reach_e3_m / space.radius_m
                       : space.kind == SpaceKind::S3 ? 4.0
                                                     : options.reach_rad;
  std::vector<glm::dmat4> cells{glm::dmat4(1.0)};
  std::vector<Point> centres{o};
  std::deque<std::size_t> queue{0};
  const double tol = 1e-6 * space.radius_m;
  while (!queue.empty() && cells.size() < options.max_cells) {
    const glm::dmat4 g = cells[queue.front()];
    queue.pop_front();
    for (const auto& m : mirrors) {
      const glm::dmat4 h = g * m;
      const Point c = h * o;
      if (geometry::distance_from_origin_rad(space, c) > reach) continue;
      bool seen = false;
      for (const Point& e : centres)
        if (glm::length(e - c) < tol) {
          seen = true;
          break;
        }
      if (seen) continue;
      cells.push_back(h);
      centres.push_back(c);
      queue.push_back(cells.size() - 1);
      if (cells.size() >= options.max_cells) break;
    }
  }
  t.cells = cells.size();
  // Unique edges, keyed by their quantised midpoint sum.
  std::map<std::tuple<long, long, long, long>, bool> seen;
  const double q = 1e4 / space.radius_m;
  for (const auto& g : cells)
    for (const auto& [i, j] : cell.edges) {
      const Point a = g * verts[i];
      const Point b = g * verts[j];
      const Vec4 s = (a + b) * q;
      const auto key = std::make_tuple(std::lround(s.x), std::lround(s.y), std::lround(s.z),
                                       std::lround(s.w));
      if (seen.emplace(key, true).second) t.edges.push_back({a, b});
    }
  return t;
}

std::vector<Tiling> split_into_shells(const Space& space, const Tiling& tiling, int shells) {
  std::vector<std::pair<double, std::size_t>> by_distance;
  for (std::size_t i = 0; i < tiling.edges.size(); ++i) {
    const Point mid = geometry::geodesic_lerp(space, tiling.edges[i].a, tiling.edges[i].b, 0.5);
    by_distance.emplace_back(geometry::distance_from_origin_rad(space, mid), i);
  }
  std::sort(by_distance.begin(), by_distance.end());
  std::vector<Tiling> out;
  const std::size_t per = (by_distance.size() + shells - 1) / std::max(1, shells);
  for (std::size_t start = 0; start < by_distance.size(); start += per) {
    Tiling t = tiling;
    t.edges.clear();
    for (std::size_t i = start; i < std::min(by_distance.size(), start + per); ++i)
      t.edges.push_back(tiling.edges[by_distance[i].second]);
    out.push_back(std::move(t));
  }
  return out;
}

MeshData build_tiling_mesh(const Space& space, const Tiling& tiling, int level) {
  MeshData m;
  m.topology = Topology::lines;
  m.shading = Shading::unlit;
  const int pieces = 1 << std::max(0, level);
  const double far_rad = space.kind == SpaceKind::S3 ? std::numbers::pi : 2.5;
  for (const auto& e : tiling.edges) {
    const auto first = static_cast<std::uint32_t>(m.vertices.size());
    for (int i = 0; i <= pieces; ++i) {
      const Point p = geometry::geodesic_lerp(space, e.a, e.b, static_cast<double>(i) / pieces);
      const double d = geometry::distance_from_origin_rad(space, p) /
                       (space.kind == SpaceKind::E3 ? 3.0 / space.radius_m : far_rad);
      const float f = static_cast<float>(std::clamp(1.0 - 0.75 * d, 0.2, 1.0));
      m.vertices.push_back({glm::vec4(p), glm::vec4(0.0f, 1.0f, 0.0f, 0.0f),
                            display(0.55f * f, 0.75f * f, 1.0f * f)});
    }
    for (int i = 0; i < pieces; ++i)
      m.indices.insert(m.indices.end(), {first + static_cast<std::uint32_t>(i),
                                         first + static_cast<std::uint32_t>(i + 1)});
  }
  return m;
}

MeshInfo tiling_info(const Space& space, const Tiling& tiling) {
  MeshInfo info;
  info.bounds.push_back({geometry::origin(space), 1e30});  // everywhere: never culled
  // Probes: up to 40 edges spread over the list.
  const std::size_t step = std::max<std::size_t>(1, tiling.edges.size() / 40);
  for (std::size_t i = 0; i < tiling.edges.size(); i += step) info.long_edges.push_back(tiling.edges[i]);
  info.base_segments = 1;
  return info;
}

}  // namespace curvlab::renderer
