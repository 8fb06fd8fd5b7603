// CPU meshes in model coordinates: 4-vector positions in metres on the space,
// 4-vector unit normals tangent at each position, colours. Builders take a
// subdivision level: level L splits every long (geodesic) edge into 2^L times
// its base count of pieces, which only the native view needs (its log map
// bends geodesics; the tourist projection keeps them straight).
#pragma once

#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tube.hpp"
#include "curvlab/renderer/view.hpp"

#include <glm/vec4.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::renderer {

struct Vertex {
  glm::vec4 position;  // metres, model coordinates
  glm::vec4 normal;    // unit tangent vector at position (g-norm)
  glm::vec4 color;     // linear RGBA; text panels: atlas uv in xy
};

// A vertex of a tube drawn as a screen-space ribbon (shaders/tube.vert): a
// point of the tube's centre line, the line's unit tangent there and two unit
// normals completing the frame (all model coordinates), the colour design,
// and where along and across the ribbon the vertex lies.
struct TubeVertex {
  glm::vec4 axis;
  glm::vec4 tangent;
  glm::vec4 up;    // the cross-section's φ = 0 direction
  glm::vec4 side;  // φ = 90°
  // x: the butt-to-shaft joint, y: where the tip starts, z: half the length
  // (metres along the centre line from its middle), w: 1 with rings.
  glm::vec4 design;
  // x: side of the ribbon (−1, +1); y: −1 / +1 for the rows that extend the
  // ribbon past the butt / tip end, else 0; z: u (metres from the middle);
  // w: the tube's radius in metres.
  glm::vec4 place;
};

// The clip position tube.vert gives v (its C++ twin, for the plain-loop
// baseline): the projected centre line plus the ribbon's offsets in pixels
// for a target of the given size. The vulkan test TubeShaderMatchesCpp runs
// tube.vert's computation (shaders/tube.glsl) on the same inputs and compares.
glm::dvec4 tube_clip_position(const ViewConstants& view, Hemisphere hemi, const glm::dmat4& model_view,
                              const TubeVertex& v, double width_px, double height_px);

enum class Topology { triangles, lines };
// tube: TubeVertex ribbons, coverage computed in the fragment shader.
enum class Shading { lit = 0, unlit = 1, text = 2, tube = 3 };

struct MeshData {
  Topology topology = Topology::triangles;
  Shading shading = Shading::lit;
  std::vector<Vertex> vertices;
  std::vector<TubeVertex> tube_vertices;  // Shading::tube only
  std::vector<std::uint32_t> indices;

  [[nodiscard]] std::size_t primitive_count() const {
    return indices.size() / (topology == Topology::triangles ? 3 : 2);
  }
};

// Level-independent facts the render plan uses without building a mesh.
struct BoundingBall {
  Point centre;           // model coordinates
  double radius_m = 0.0;  // geodesic radius; ≥ 1e29 means "everywhere"
};

struct MeshInfo {
  // Balls whose union holds the mesh: several small ones cull better than
  // one large one (in S3 a large ball may hold the viewer, and then its
  // antipodal image can be anywhere).
  std::vector<BoundingBall> bounds;
  std::vector<GeodesicEdge> long_edges;  // probes for native subdivision
  int base_segments = 1;         // pieces per long edge at level 0
};

// The unit normal at p in direction of the (approximate) tangent v:
// v projected to p's tangent space and normalised with g.
glm::dvec4 tangent_normal(const Space& space, const Point& p, const glm::dvec4& v);

struct TableStyle {
  double cushion_width_m = 0.05;
  double cushion_height_m = 0.035;
  double rail_width_m = 0.07;
  double skirt_depth_m = 0.12;
  // Signed convexity of the cloth: the centre rises by this much above the
  // edges (negative: sinks), along a parabolic profile in the fan's radial
  // fraction; the edges and cushions stay where they are.
  double cloth_sagitta_m = 0.0;
};

// The table centred at the model origin, cloth in the plane y = 0 (the model
// frame of geometry/table.hpp): cloth, cushions, wooden rails and a skirt.
MeshData build_table(const Space& space, const geometry::TableShape& table, int level,
                     const TableStyle& style = {});
MeshInfo table_info(const Space& space, const geometry::TableShape& table,
                    const TableStyle& style = {});

// Marks along the cue stick (StickMarks, vocabulary.hpp). `rings`: light
// bands centred at the fractions kStickRingFractions of the length (−½ the
// butt end, +½ the tip), each brightening the wood along a tent profile of
// half-width kStickRingHalfWidthM so that the band's image position can be
// read to a fraction of a pixel with or without anti-aliasing (a sharp-edged
// band quantizes to whole pixels).
inline constexpr std::array<double, 5> kStickRingFractions{-0.4, -0.2, 0.0, 0.2, 0.4};
inline constexpr double kStickRingHalfWidthM = 0.012;
inline constexpr double kStickButtFraction = 0.35;
inline constexpr double kStickTipM = 0.02;

// The cue stick of geometry/tube.hpp with its chord along the model x axis,
// centred at the model origin, bowed toward +z by the sagitta. Tip white
// (the last kStickTipM), shaft light wood, butt dark (the first
// kStickButtFraction of the length); optional rings. Drawn as a ribbon
// (Shading::tube) whose edges, ends and colour joints are anti-aliased
// analytically: every pixel's coverage is computed, not sampled, so an edge's
// image position is carried to a small fraction of a pixel at any MSAA count.
MeshData build_stick(const Space& space, const geometry::BentStick& stick, int level,
                     StickMarks marks = StickMarks::none);
MeshInfo stick_info(const Space& space, const geometry::BentStick& stick);

// A ball of the given radius centred at the model origin.
// A ball; with `marking`, two polar caps of that colour (30° across) that
// show how the ball turns.
MeshData build_ball(const Space& space, double radius_m, const glm::vec4& color,
                    const std::optional<glm::vec4>& marking = std::nullopt);
MeshInfo ball_info(const Space& space, double radius_m);

// A flat panel in the geodesic plane z = 0 of the model frame, centred on the
// origin, facing +z; uv (0,0) top-left … (1,1) bottom-right in colour.xy.
MeshData build_panel(const Space& space, double width_m, double height_m, int level);
MeshInfo panel_info(const Space& space, double width_m, double height_m);
// A head-locked panel's card (scene.hpp): the rectangle |x| ≤ half_w,
// |y| ≤ half_h in the plane z = 0, Euclidean (x, y, z, 1), atlas
// coordinates in the colour.
MeshData build_head_panel(double half_w_m, double half_h_m);

}  // namespace curvlab::renderer
