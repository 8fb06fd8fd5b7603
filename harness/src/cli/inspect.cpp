// `curvlab inspect …`: the numbers a methods developer checks a protocol
// against (table shapes, holonomy, the native map).
#include "common.hpp"

#include "curvlab/geometry/holonomy.hpp"
#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/table.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <memory>
#include <numbers>
#include <sstream>

namespace curvlab::harness::cli {
namespace {

using namespace curvlab::geometry;

void require_positive(double value, const std::string& option) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw UsageError(option + " must be a positive finite number of metres");
}

Json vec_json(const Vec3& v) { return Json::array({v.x, v.y, v.z}); }

struct TableArgs {
  SpaceKind kind = SpaceKind::E3;
  double edge_m = 0.0;
  int sides = 0;
  double radius_m = 0.0;
  bool json = false;
};

void run_table(const TableArgs& a, bool edge_given, bool radius_given) {
  const int sides = a.sides > 0 ? a.sides : default_table_sides(a.kind);
  std::variant<TableShape, GeometryError> result;
  if (a.kind == SpaceKind::E3) {
    if (!edge_given) throw UsageError("--edge-m is required in E3 (the square's edge is free)");
    require_positive(a.edge_m, "--edge-m");
    const double radius = radius_given ? a.radius_m : 1.0;
    require_positive(radius, "--radius-m");
    result = right_angled_table_from_edge(a.kind, a.edge_m, sides, radius);
  } else if (edge_given && radius_given) {
    throw UsageError("--edge-m and --radius-m both given: in " +
                     std::string(to_string(a.kind)) +
                     " the edge of a right-angled table fixes the radius; give one");
  } else if (edge_given) {
    require_positive(a.edge_m, "--edge-m");
    result = right_angled_table_from_edge(a.kind, a.edge_m, sides);
  } else if (radius_given) {
    require_positive(a.radius_m, "--radius-m");
    result = right_angled_table_from_radius(Space{a.kind, a.radius_m}, sides);
  } else {
    throw UsageError("give --edge-m (the physical edge) or --radius-m");
  }
  if (const auto* err = std::get_if<GeometryError>(&result)) throw UsageError(err->message);
  const auto& t = std::get<TableShape>(result);
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["sides"] = t.sides;
  doc["side_rad"] = t.side_rad;
  doc["edge_m"] = t.edge_m;
  doc["radius_m"] = t.radius_m;
  doc["interior_angle_deg"] = t.interior_angle_rad * 180.0 / std::numbers::pi;
  doc["circumradius_m"] = t.circumradius_m();
  doc["apothem_m"] = t.apothem_m();
  doc["physical_laps_per_virtual_lap"] = t.physical_laps_per_virtual_lap();
  print_result(doc, a.json);
}

struct HolonomyArgs {
  SpaceKind kind = SpaceKind::S3;
  double theta_rad = 0.0;
  bool json = false;
};

void run_holonomy(const HolonomyArgs& a) {
  if (!std::isfinite(a.theta_rad) || a.theta_rad <= 0.0)
    throw UsageError("--theta-rad must be a positive finite number of radians");
  if (a.kind == SpaceKind::S3 && a.theta_rad >= std::numbers::pi)
    throw UsageError("--theta-rad must be below π in S3 (each side of the square is a "
                     "geodesic segment shorter than half a great circle)");
  const Space space{a.kind, 1.0};
  const HolonomyResult h = head_square(space, a.theta_rad);
  const double t = a.theta_rad;
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["theta_rad"] = t;
  doc["rotation_rad"] = h.rotation_rad;
  doc["offset_rad"] = h.offset_rad;
  doc["rotation_small_theta_rad"] = space.k() * t * t;
  doc["offset_small_theta_rad"] = std::abs(space.k()) * t * t * t / std::sqrt(2.0);
  Json m = Json::array();
  for (int row = 0; row < 4; ++row) {
    Json r = Json::array();
    for (int c = 0; c < 4; ++c) r.push_back(h.final_pose.m[c][row]);
    m.push_back(r);
  }
  doc["final_pose"] = m;
  print_result(doc, a.json);
}

struct MapArgs {
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 1.0;
  std::string point;
  bool json = false;
};

void run_map(const MapArgs& a) {
  require_positive(a.radius_m, "--radius-m");
  const auto v = parse_number_list(a.point, "--point", 4);
  const Space space{a.kind, a.radius_m};
  const Point p(v[0], v[1], v[2], v[3]);
  const double err = off_space_error(space, p);
  if (!(err <= 1e-9)) {
    std::ostringstream os;
    os << std::setprecision(10) << "--point (" << a.point << ") is not on "
       << to_string(a.kind) << " of radius " << a.radius_m << " m: ";
    switch (a.kind) {
      case SpaceKind::S3:
        os << "expected x²+y²+z²+w² = ρ² = " << a.radius_m * a.radius_m << ", got "
           << p.x * p.x + p.y * p.y + p.z * p.z + p.w * p.w;
        break;
      case SpaceKind::E3:
        os << "expected w = ρ = " << a.radius_m << ", got w = " << p.w;
        break;
      case SpaceKind::H3:
        os << "expected x²+y²+z²−w² = −ρ² = " << -a.radius_m * a.radius_m
           << " with w > 0, got " << p.x * p.x + p.y * p.y + p.z * p.z - p.w * p.w
           << " with w = " << p.w;
        break;
    }
    os << " (relative tolerance 1e-9)";
    throw UsageError(os.str());
  }
  const double theta = distance_from_origin_rad(space, p);
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["radius_m"] = a.radius_m;
  doc["theta_rad"] = theta;
  doc["distance_m"] = theta * a.radius_m;
  doc["native_m"] = vec_json(log_origin(space, p));
  if (a.kind == SpaceKind::S3) doc["back_native_m"] = vec_json(back_log_origin(space, p));
  print_result(doc, a.json);
}

}  // namespace

void add_inspect_commands(CLI::App& app) {
  auto* inspect = app.add_subcommand("inspect", "print the geometry behind a protocol's numbers");
  inspect->require_subcommand(1);

  {
    auto args = std::make_shared<TableArgs>();
    auto* cmd = inspect->add_subcommand(
        "table", "the right-angled regular table of a space (paper, 'Construction of the "
                 "billiards tables')");
    add_space_option(cmd, &args->kind);
    auto* edge = cmd->add_option("--edge-m", args->edge_m, "edge length in metres (fixes ρ in S3/H3)");
    cmd->add_option("--sides", args->sides, "number of sides (S3: 3, E3: 4, H3: ≥ 5; default per space)")
        ->check(CLI::Range(2, 1000));
    auto* radius = cmd->add_option("--radius-m", args->radius_m,
                                   "radius ρ in metres (E3: default 1; S3/H3: instead of --edge-m)");
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->callback([args, edge, radius] { run_table(*args, edge->count() > 0, radius->count() > 0); });
  }
  {
    auto args = std::make_shared<HolonomyArgs>();
    auto* cmd = inspect->add_subcommand(
        "holonomy", "the paper's head-square under naive tracking: final rotation and offset");
    add_space_option(cmd, &args->kind);
    cmd->add_option("--theta-rad", args->theta_rad, "side of the square in radians (d/ρ)")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->callback([args] { run_holonomy(*args); });
  }
  {
    auto args = std::make_shared<MapArgs>();
    auto* cmd = inspect->add_subcommand(
        "map", "distance and azimuthal-equidistant (native) image of a point seen from the origin");
    add_space_option(cmd, &args->kind);
    cmd->add_option("--radius-m", args->radius_m, "radius ρ in metres")->required();
    cmd->add_option("--point", args->point, "the point as x,y,z,w in metres")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->callback([args] { run_map(*args); });
  }
}

}  // namespace curvlab::harness::cli
