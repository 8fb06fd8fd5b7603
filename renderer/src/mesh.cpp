#include "curvlab/renderer/mesh.hpp"

#include "curvlab/renderer/colour.hpp"

#include "curvlab/geometry/maps.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <numbers>

namespace curvlab::renderer {

using geometry::Vec3;
using geometry::Vec4;

glm::dvec4 tangent_normal(const Space& space, const Point& p, const glm::dvec4& v) {
  const double rho2 = space.radius_m * space.radius_m;
  const glm::dvec4 t = v - (geometry::point_form(space, p, v) / rho2) * p;
  const double n2 = geometry::vector_form(space, t, t);
  return n2 > 0.0 ? t / std::sqrt(n2) : glm::dvec4(0.0, 1.0, 0.0, 0.0);
}

namespace {

constexpr double kPi = std::numbers::pi;

int pieces(int base, int level) { return base << std::max(0, level); }

// Appends a vertex; the normal is the tangent direction toward `outward`
// (a nearby point off the surface), which keeps normals exact in every space.
void push(MeshData& m, const Space& space, const Point& p, const Point& outward,
          const glm::vec4& color) {
  const glm::dvec4 n = tangent_normal(space, p, outward - p);
  m.vertices.push_back({glm::vec4(p), glm::vec4(n), color});
}

// A quad strip grid: rows × cols vertices already pushed from `first`, row major.
void grid_indices(MeshData& m, std::uint32_t first, int rows, int cols) {
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < cols; ++c) {
      const auto i = first + static_cast<std::uint32_t>(r * cols + c);
      const auto cu = static_cast<std::uint32_t>(cols);
      m.indices.insert(m.indices.end(), {i, i + cu, i + 1, i + 1, i + cu, i + cu + 1});
    }
}

// A surface patch of the Fermi "box" around one table edge: (s, y, z) →
// frame(s)·exp(0, y, z), s along the edge. `normal_dir` gives the outward
// offset (in the local y/z plane) used for normals.
void fermi_patch(MeshData& m, const Space& space, const geometry::TableShape& table, int edge,
                 double s0, double s1, int ns, glm::dvec2 yz0, glm::dvec2 yz1, int nyz,
                 glm::dvec2 normal_dir, const glm::vec4& color) {
  const auto first = static_cast<std::uint32_t>(m.vertices.size());
  constexpr double kEps = 1e-3;
  for (int i = 0; i <= ns; ++i) {
    const double s = s0 + (s1 - s0) * i / ns;
    const Isometry f = geometry::table_edge_frame(space, table, edge, s);
    for (int j = 0; j <= nyz; ++j) {
      const glm::dvec2 yz = yz0 + (yz1 - yz0) * (static_cast<double>(j) / nyz);
      const Point p = f * geometry::exp_origin(space, Vec3(0.0, yz.x, yz.y));
      const glm::dvec2 o = yz + kEps * normal_dir;
      const Point out = f * geometry::exp_origin(space, Vec3(0.0, o.x, o.y));
      push(m, space, p, out, color);
    }
  }
  grid_indices(m, first, ns + 1, nyz + 1);
}

const glm::vec4& kCloth = palette::cloth;
const glm::vec4& kCushion = palette::cushion;
const glm::vec4& kRail = palette::rail;
const glm::vec4& kSkirt = palette::skirt;

}  // namespace

MeshData build_table(const Space& space, const geometry::TableShape& table, int level,
                     const TableStyle& style) {
  MeshData m;
  const int n = table.sides;
  const Point centre = geometry::origin(space);
  // Cloth: fan triangles (centre, corner j, corner j+1). The outer edge — the
  // only line a viewer can see on the flat cloth — gets the level's 2^level
  // pieces; the interior gets at most 4 rows, each with pieces in proportion
  // to its length, so the triangle count grows linearly with the level, not
  // quadratically. Points are normalised linear combinations, which stay in
  // the totally geodesic plane y = 0.
  const int div = pieces(1, level);
  const int rows = std::min(div, 4);
  for (int j = 0; j < n; ++j) {
    const Point a = geometry::table_corner(space, table, j);
    const Point b = geometry::table_corner(space, table, j + 1);
    std::vector<std::uint32_t> row_start;
    std::vector<int> row_pieces;
    for (int r = 0; r <= rows; ++r) {
      const double fr = static_cast<double>(r) / rows;
      const int np = r == 0 ? 0 : std::max(1, (div * r + rows - 1) / rows);
      row_start.push_back(static_cast<std::uint32_t>(m.vertices.size()));
      row_pieces.push_back(np);
      for (int c = 0; c <= np; ++c) {
        const double fc = np == 0 ? 0.0 : static_cast<double>(c) / np;
        const Vec4 lin = (1.0 - fr) * centre + fr * ((1.0 - fc) * a + fc * b);
        Point p = geometry::normalize_point(space, lin);
        if (style.cloth_sagitta_m != 0.0) {
          // Raise p along the plane's normal by a geodesic of the profile's
          // height: the translation taking the origin to p within the plane
          // carries the origin's normal e_y to p's.
          const double h = style.cloth_sagitta_m * (1.0 - fr * fr);
          p = geometry::translation_to(space, p).m *
              geometry::translation_m(space, Vec3(0.0, h, 0.0)).m * centre;
        }
        m.vertices.push_back({glm::vec4(p), glm::vec4(0, 1, 0, 0), kCloth});
      }
    }
    // Stitch neighbouring rows by walking both in order of their parameter.
    for (int r = 0; r < rows; ++r) {
      const std::uint32_t top = row_start[r];
      const std::uint32_t bot = row_start[r + 1];
      const int nt = row_pieces[r];
      const int nb = row_pieces[r + 1];
      int i = 0;
      int k = 0;
      while (i < nt || k < nb) {
        const double next_top = nt == 0 ? 2.0 : static_cast<double>(i + 1) / nt;
        const double next_bot = static_cast<double>(k + 1) / nb;
        const auto ti = top + static_cast<std::uint32_t>(i);
        const auto bk = bot + static_cast<std::uint32_t>(k);
        if (k < nb && (i >= nt || next_bot <= next_top)) {
          m.indices.insert(m.indices.end(), {ti, bk + 1, bk});
          ++k;
        } else {
          m.indices.insert(m.indices.end(), {ti, ti + 1, bk});
          ++i;
        }
      }
    }
  }
  // Cushions, rails and skirt in each edge's Fermi coordinates. They extend
  // past the corners by their own width so neighbouring edges meet (the
  // corners are right angles).
  const double cw = style.cushion_width_m;
  const double ch = style.cushion_height_m;
  const double rw = style.rail_width_m;
  const double outer = cw + rw;
  // The cushion's inner bottom edge is the cloth's geodesic edge, which the
  // level's 2^level pieces keep within the error budget; 8 pieces carry the
  // equidistant (non-geodesic) rail curves in every view.
  const int ns = std::max(8, pieces(1, level));
  for (int e = 0; e < n; ++e) {
    const double s0 = 0.0;
    const double s1 = table.edge_m;
    const double so0 = -outer;
    const double so1 = table.edge_m + outer;
    // Cushion: inner face, top.
    fermi_patch(m, space, table, e, s0, s1, ns, {ch, 0.0}, {0.0, 0.0}, 1, {0.0, -1.0}, kCushion);
    fermi_patch(m, space, table, e, s0 - cw, s1 + cw, ns, {ch, cw}, {ch, 0.0}, 1, {1.0, 0.0},
                kCushion);
    // Rail: top, outer face.
    fermi_patch(m, space, table, e, so0, so1, ns, {ch + 0.004, outer}, {ch + 0.004, cw}, 1,
                {1.0, 0.0}, kRail);
    fermi_patch(m, space, table, e, so0, so1, ns, {-style.skirt_depth_m, outer},
                {ch + 0.004, outer}, 2, {0.0, 1.0}, kSkirt);
    // The step between cushion top and rail top.
    fermi_patch(m, space, table, e, s0 - cw, s1 + cw, ns, {ch, cw}, {ch + 0.004, cw}, 1,
                {0.0, -1.0}, kRail);
  }
  return m;
}

MeshInfo table_info(const Space& space, const geometry::TableShape& table,
                    const TableStyle& style) {
  MeshInfo info;
  // The cloth within the circumradius, and each edge's cushions, rails and
  // skirt in four balls along it.
  info.bounds.push_back({geometry::origin(space), table.circumradius_m()});
  const double outer = style.cushion_width_m + style.rail_width_m;
  const double piece_m = table.edge_m / 4.0;
  const double ball_r = std::hypot(piece_m / 2.0 + outer,
                                   std::hypot(outer, style.skirt_depth_m + style.cushion_height_m)) + 0.01;
  for (int e = 0; e < table.sides; ++e)
    for (int i = 0; i < 4; ++i)
      info.bounds.push_back({geometry::table_edge_frame(space, table, e, (i + 0.5) * piece_m) *
                                 geometry::origin(space),
                             ball_r});
  for (int j = 0; j < table.sides; ++j)
    info.long_edges.push_back({geometry::table_corner(space, table, j),
                               geometry::table_corner(space, table, j + 1)});
  info.base_segments = 1;
  return info;
}

namespace {

// The ribbon vertices' ring switch (design.w, read by shaders/tube.frag): 1 draws
// the rings.
float ring_switch(StickMarks marks) {
  switch (marks) {
    case StickMarks::none: return 0.0f;
    case StickMarks::rings: return 1.0f;
  }
  std::abort();  // not a StickMarks: a broken contract
}

// The rows of the stick's ribbon: `along` equal pieces (the ribbon follows
// the bent centre line through them), plus the joint, the tip's start and,
// with rings, each band's two feet and peak, so that no colour change falls
// between rows unseen.
std::vector<double> stick_rows(const geometry::BentStick& stick, int along, StickMarks marks) {
  const double half = stick.length_m / 2.0;
  std::vector<double> u;
  for (int i = 0; i <= along; ++i) u.push_back(-half + stick.length_m * i / along);
  u.push_back(-half + kStickButtFraction * stick.length_m);
  u.push_back(half - kStickTipM);
  if (marks == StickMarks::rings)
    for (double f : kStickRingFractions)
      for (double d : {-kStickRingHalfWidthM, 0.0, kStickRingHalfWidthM})
        u.push_back(f * stick.length_m + d);
  std::sort(u.begin(), u.end());
  u.erase(std::unique(u.begin(), u.end(), [](double a, double b) { return std::abs(a - b) < 1e-9; }),
          u.end());
  return u;
}

// v with its components along the unit vectors `against` removed, normalised
// with g (tangent vectors at one point).
glm::dvec4 orthonormal(const Space& space, glm::dvec4 v, std::initializer_list<glm::dvec4> against) {
  for (const glm::dvec4& a : against) v -= geometry::vector_form(space, v, a) * a;
  return v / std::sqrt(geometry::vector_form(space, v, v));
}

}  // namespace

MeshData build_stick(const Space& space, const geometry::BentStick& stick, int level, StickMarks marks) {
  MeshData m;
  m.shading = Shading::tube;
  const Isometry frame = Isometry::identity();
  const double half = stick.length_m / 2.0;
  const glm::vec4 design(static_cast<float>(-half + kStickButtFraction * stick.length_m),
                         static_cast<float>(half - kStickTipM), static_cast<float>(half),
                         ring_switch(marks));
  // The two ends once more: the rows that carry the ribbon a little past them.
  const std::vector<double> inner = stick_rows(stick, std::max(96, pieces(12, level)), marks);
  std::vector<double> rows{-half};
  rows.insert(rows.end(), inner.begin(), inner.end());
  rows.push_back(half);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const double u = rows[i];
    const float end = i == 0 ? -1.0f : i + 1 == rows.size() ? 1.0f : 0.0f;
    const Point c = stick.centre_point(space, frame, u);
    constexpr double kDu = 1e-4;
    const glm::dvec4 t = tangent_normal(space, c, stick.centre_point(space, frame, u + kDu) -
                                                      stick.centre_point(space, frame, u - kDu));
    const glm::dvec4 up = orthonormal(space, tangent_normal(space, c, stick.surface_point(space, frame, u, 0.0) - c), {t});
    const glm::dvec4 side =
        orthonormal(space, tangent_normal(space, c, stick.surface_point(space, frame, u, kPi / 2.0) - c), {t, up});
    for (const float across : {-1.0f, 1.0f})
      m.tube_vertices.push_back({glm::vec4(c), glm::vec4(t), glm::vec4(up), glm::vec4(side), design,
                                 glm::vec4(across, end, static_cast<float>(u),
                                           static_cast<float>(stick.radius_m))});
  }
  for (std::uint32_t r = 0; r + 1 < rows.size(); ++r) {
    const std::uint32_t i = 2 * r;
    m.indices.insert(m.indices.end(), {i, i + 2, i + 1, i + 1, i + 2, i + 3});
  }
  return m;
}

glm::dvec4 tube_clip_position(const ViewConstants& view, Hemisphere hemi, const glm::dmat4& model_view,
                              const TubeVertex& v, double width_px, double height_px) {
  constexpr double kMarginPx = 1.5;  // tube.vert MARGIN_PX
  const Space& space = view.space;
  const double rho = space.radius_m;
  const glm::dvec2 size(width_px, height_px);
  const auto clip_of = [&](const glm::dvec4& q) {
    return clip_position(view, hemi, q * (rho / std::sqrt(std::max(geometry::point_form(space, q, q), 1e-300))));
  };
  const auto to_px = [&](const glm::dvec4& c) { return (glm::dvec2(c) / c.w * 0.5 + 0.5) * size; };
  const double r = double(v.place.w);
  const glm::dvec4 p = model_view * glm::dvec4(v.axis);
  const glm::dvec4 t = model_view * glm::dvec4(v.tangent);
  const glm::dvec4 n_up = model_view * glm::dvec4(v.up);
  const glm::dvec4 n_side = model_view * glm::dvec4(v.side);
  const glm::dvec4 clip = clip_of(p);
  if (clip.w <= 0.0) return {0.0, 0.0, 2.0, 1.0};
  const double sign_back = hemi == Hemisphere::back ? -1.0 : 1.0;
  const glm::dvec4 toward = tangent_normal(space, sign_back * p, glm::dvec4(0.0, 0.0, 0.0, rho));
  const double a = geometry::vector_form(space, toward, sign_back * n_up);
  const double b = geometry::vector_form(space, toward, sign_back * n_side);
  const double m = std::hypot(a, b);
  const glm::dvec2 cs = m > 1e-6 ? glm::dvec2(a, b) / m : glm::dvec2(0.0, 1.0);
  const glm::dvec4 c = cs.x * n_up + cs.y * n_side;
  const glm::dvec4 s = -cs.y * n_up + cs.x * n_side;
  const glm::dvec2 centre = to_px(clip);
  const glm::dvec2 along = to_px(clip_of(p + r * t)) - centre;
  const double px_per_m = glm::length(along) / r;
  const glm::dvec2 dir = px_per_m > 0.0 ? along / (px_per_m * r) : glm::dvec2(1.0, 0.0);
  const glm::dvec2 normal(-dir.y, dir.x);
  const glm::dvec4 front = clip_of(p + sign_back * r * c);
  const glm::dvec2 to_front = to_px(front) - centre;
  const glm::dvec2 to_aside = to_px(clip_of(p + r * s)) - centre;
  const double half_px = std::hypot(glm::dot(normal, to_front), glm::dot(normal, to_aside));
  glm::dvec2 at = centre + double(v.place.x) * (half_px + kMarginPx) * normal;
  const double beyond = 1.25 * std::hypot(glm::dot(dir, to_front), glm::dot(dir, to_aside)) + kMarginPx;
  if (v.place.y != 0.0f) at += double(v.place.y) * beyond * dir;
  return {(at / size * 2.0 - 1.0) * clip.w, front.z / front.w * clip.w, clip.w};
}

MeshInfo stick_info(const Space& space, const geometry::BentStick& stick) {
  MeshInfo info;
  info.bounds.push_back({geometry::origin(space),
                         stick.length_m / 2.0 + std::abs(stick.sagitta_m) + stick.radius_m});
  const Isometry frame = Isometry::identity();
  info.long_edges.push_back({stick.centre_point(space, frame, -stick.length_m / 2.0),
                             stick.centre_point(space, frame, stick.length_m / 2.0)});
  info.base_segments = 12;
  return info;
}

MeshData build_ball(const Space& space, double radius_m, const glm::vec4& color,
                    const std::optional<glm::vec4>& marking) {
  MeshData m;
  constexpr int kRings = 12;
  constexpr int kSlices = 18;
  for (int r = 0; r <= kRings; ++r) {
    const double lat = kPi * r / kRings;
    for (int s = 0; s <= kSlices; ++s) {
      const double lon = 2.0 * kPi * s / kSlices;
      const Vec3 dir(std::sin(lat) * std::cos(lon), std::cos(lat), std::sin(lat) * std::sin(lon));
      const Point p = geometry::exp_origin(space, radius_m * dir);
      const Point out = geometry::exp_origin(space, (radius_m + 1e-3) * dir);
      const bool cap = marking && (r <= 1 || r >= kRings - 1);
      push(m, space, p, out, cap ? *marking : color);
    }
  }
  grid_indices(m, 0, kRings + 1, kSlices + 1);
  return m;
}

MeshInfo ball_info(const Space& space, double radius_m) {
  MeshInfo info;
  info.bounds.push_back({geometry::origin(space), radius_m});
  return info;
}

MeshData build_panel(const Space& space, double width_m, double height_m, int level) {
  MeshData m;
  m.shading = Shading::text;
  const int nx = pieces(2, level);
  const int ny = pieces(1, level);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double u = static_cast<double>(i) / nx;
      const double v = static_cast<double>(j) / ny;
      const Vec3 local((u - 0.5) * width_m, (0.5 - v) * height_m, 0.0);
      const Point p = geometry::exp_origin(space, local);
      const Point out = geometry::exp_origin(space, local + Vec3(0.0, 0.0, 1e-3));
      const glm::dvec4 n = tangent_normal(space, p, out - p);
      m.vertices.push_back({glm::vec4(p), glm::vec4(n),
                            glm::vec4(static_cast<float>(u), static_cast<float>(v), 0.0f, 1.0f)});
    }
  grid_indices(m, 0, ny + 1, nx + 1);
  return m;
}

MeshData build_head_panel(double half_w_m, double half_h_m) {
  MeshData m;
  m.shading = Shading::text;
  for (int j = 0; j <= 1; ++j)
    for (int i = 0; i <= 1; ++i) {
      const auto u = static_cast<float>(i);
      const auto v = static_cast<float>(j);
      m.vertices.push_back({glm::vec4(static_cast<float>((2.0 * i - 1.0) * half_w_m),
                                      static_cast<float>((1.0 - 2.0 * j) * half_h_m), 0.0f, 1.0f),
                            glm::vec4(0.0f, 0.0f, 1.0f, 0.0f), glm::vec4(u, v, 0.0f, 1.0f)});
    }
  grid_indices(m, 0, 2, 2);
  return m;
}

MeshInfo panel_info(const Space& space, double width_m, double height_m) {
  MeshInfo info;
  info.bounds.push_back({geometry::origin(space), 0.5 * std::hypot(width_m, height_m)});
  const double hw = width_m / 2.0;
  const double hh = height_m / 2.0;
  info.long_edges.push_back({geometry::exp_origin(space, Vec3(-hw, hh, 0.0)),
                             geometry::exp_origin(space, Vec3(hw, hh, 0.0))});
  info.long_edges.push_back({geometry::exp_origin(space, Vec3(-hw, -hh, 0.0)),
                             geometry::exp_origin(space, Vec3(hw, -hh, 0.0))});
  info.base_segments = 2;
  return info;
}

}  // namespace curvlab::renderer
