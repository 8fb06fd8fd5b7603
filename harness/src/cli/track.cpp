// `curvlab trajectory …`, `curvlab track …`, `curvlab inspect vergence` and
// `curvlab inspect stick`: scripted lab trajectories, the tracking algorithms
// run over them, and the binocular perception model's numbers.
#include "common.hpp"

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/geometry/trajectory.hpp"
#include "curvlab/harness/tracking/trajectory_csv.hpp"

#include <CLI/CLI.hpp>

#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>

namespace curvlab::harness::cli {
namespace {

using namespace curvlab::geometry;

constexpr double kPi = std::numbers::pi;

void require_positive(double value, const std::string& option, const std::string& unit) {
  if (!(value > 0.0) || !std::isfinite(value))
    throw UsageError(option + " must be a positive finite number of " + unit);
}

void require_finite(double value, const std::string& option) {
  if (!std::isfinite(value)) throw UsageError(option + " must be a finite number");
}

// The views `inspect stick` takes: those with two eyes (one eye sees no bow).
std::vector<std::string_view> binocular_views() {
  std::vector<std::string_view> out;
  for (const ViewPreset preset : kViewPresets)
    if (binocular(preset)) out.push_back(to_string(preset));
  return out;
}

// Names as CLI11's IsMember takes them.
std::vector<std::string> member_names(const std::vector<std::string_view>& names) {
  return {names.begin(), names.end()};
}

// ---- curvlab trajectory -------------------------------------------------

struct TrajectoryArgs {
  std::string out;
  TrajectoryCommon common;
  double laps = 1.0;
  std::string direction = "ccw";
  double speed_m_s = 0.0;  // 0: the generator's default
  double side_m = 0.30;
  double overshoot_m = 0.20;
  double lean_height_m = 1.20;
};

void add_common_trajectory_options(CLI::App* cmd, TrajectoryArgs* a) {
  cmd->add_option("--out", a->out, "CSV file to write (format: docs/tracking.md)")->required();
  cmd->add_option("--rate-hz", a->common.rate_hz, "frame rate (default 90)");
  cmd->add_option("--table-edge-m", a->common.table.edge_m, "physical table edge (default 0.90)");
  cmd->add_option("--table-height-m", a->common.table.height_m, "table top height (default 0.75)");
  cmd->add_option("--head-height-m", a->common.head_height_m, "standing eye height (default 1.60)");
  cmd->add_option("--head-distance-m", a->common.head_distance_m,
                  "standing distance from the table edge (default 0.35)");
  cmd->add_option("--hand-spread-m", a->common.hand_spread_m,
                  "hands this far along the rail either side of the head (default 0.25)");
  cmd->add_option("--speed-m-s", a->speed_m_s, "walking / moving speed");
}

void check_common(const TrajectoryArgs& a) {
  require_positive(a.common.rate_hz, "--rate-hz", "hertz");
  require_positive(a.common.table.edge_m, "--table-edge-m", "metres");
  require_finite(a.common.table.height_m, "--table-height-m");
  require_finite(a.common.head_height_m, "--head-height-m");
  require_positive(a.common.head_distance_m, "--head-distance-m", "metres");
  require_finite(a.common.hand_spread_m, "--hand-spread-m");
  if (a.speed_m_s != 0.0) require_positive(a.speed_m_s, "--speed-m-s", "metres per second");
}

void write_and_report(const TrajectoryArgs& a, const Trajectory& t, const std::string& kind) {
  std::ofstream out(a.out);
  if (!out) throw RuntimeFailure(a.out + ": cannot open for writing");
  harness::write_trajectory_csv(out, t, a.common.table);
  out.close();
  if (!out) throw RuntimeFailure(a.out + ": write failed");
  Json doc;
  doc["trajectory"] = kind;
  doc["frames"] = t.size();
  doc["duration_s"] = t.empty() ? 0.0 : static_cast<double>(t.back().t_ns - t.front().t_ns) * 1e-9;
  doc["out"] = a.out;
  print_result(doc, false);
}

void run_trajectory(const std::string& kind, const TrajectoryArgs& a) {
  check_common(a);
  Trajectory t;
  if (kind == "walk-around") {
    require_finite(a.laps, "--laps");
    if (a.laps < 0.0) throw UsageError("--laps must be ≥ 0 (use --direction cw to walk clockwise)");
    if (a.laps > 1000.0) throw UsageError("--laps must be at most 1000");
    WalkAroundOptions o;
    o.common = a.common;
    o.laps = a.laps;
    o.direction = a.direction == "cw" ? -1 : +1;
    if (a.speed_m_s > 0.0) o.speed_m_s = a.speed_m_s;
    t = walk_around(o);
  } else if (kind == "head-square") {
    require_positive(a.side_m, "--side-m", "metres");
    if (a.side_m > a.common.head_distance_m + 0.5 * a.common.table.edge_m)
      throw UsageError("--side-m must not take the head past the table centre (at most " +
                       std::to_string(a.common.head_distance_m + 0.5 * a.common.table.edge_m) +
                       " m)");
    HeadSquareOptions o;
    o.common = a.common;
    o.side_m = a.side_m;
    if (a.speed_m_s > 0.0) o.speed_m_s = a.speed_m_s;
    t = head_square(o);
  } else if (kind == "hand-lap") {
    require_finite(a.laps, "--laps");
    if (a.laps == 0.0 || std::abs(a.laps) > 100.0)
      throw UsageError("--laps must be non-zero and at most 100 in size (negative: clockwise)");
    HandLapOptions o;
    o.common = a.common;
    o.laps = a.direction == "cw" ? -std::abs(a.laps) : a.laps;
    if (a.speed_m_s > 0.0) o.speed_m_s = a.speed_m_s;
    t = hand_lap(o);
  } else {
    require_finite(a.overshoot_m, "--overshoot-m");
    if (a.overshoot_m < 0.0 || a.overshoot_m > 0.5 * a.common.table.edge_m)
      throw UsageError("--overshoot-m must be between 0 and half the table edge (metres past the centre)");
    require_finite(a.lean_height_m, "--lean-height-m");
    LeanOverCentreOptions o;
    o.common = a.common;
    o.overshoot_m = a.overshoot_m;
    o.lean_height_m = a.lean_height_m;
    if (a.speed_m_s > 0.0) o.speed_m_s = a.speed_m_s;
    t = lean_over_centre(o);
  }
  write_and_report(a, t, kind);
}

// ---- curvlab track ------------------------------------------------------

struct TrackArgs {
  std::string trajectory;
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 0.0;
  double edge_m = 0.0;
  int sides = 0;
  std::string algorithm;
  bool json = false;
  std::string out;
};

TableShape resolve_table(const TrackArgs& a, bool radius_given, bool edge_given,
                         const PhysicalTable& physical) {
  const int sides = a.sides > 0 ? a.sides : default_table_sides(a.kind);
  if (radius_given) require_positive(a.radius_m, "--radius-m", "metres");
  if (edge_given) require_positive(a.edge_m, "--edge-m", "metres");
  std::variant<TableShape, GeometryError> r;
  if (a.kind == SpaceKind::E3) {
    r = right_angled_table_from_edge(a.kind, edge_given ? a.edge_m : physical.edge_m, sides,
                                     radius_given ? a.radius_m : 1.0);
  } else if (radius_given && edge_given) {
    throw UsageError("--radius-m and --edge-m both given: in " + std::string(to_string(a.kind)) +
                     " the table's edge fixes ρ; give one");
  } else if (radius_given) {
    r = right_angled_table_from_radius(Space{a.kind, a.radius_m}, sides);
  } else {
    r = right_angled_table_from_edge(a.kind, edge_given ? a.edge_m : physical.edge_m, sides);
  }
  if (const auto* e = std::get_if<GeometryError>(&r)) throw UsageError(e->message);
  return std::get<TableShape>(r);
}

void run_track(const TrackArgs& a, bool radius_given, bool edge_given) {
  auto parsed = harness::read_trajectory_csv(a.trajectory);
  if (!parsed) raise(parsed.error());
  const auto& file = parsed.value();
  const TableShape table = resolve_table(a, radius_given, edge_given, file.table);
  const Space space{a.kind, table.radius_m};
  const auto algorithm = parse_tracking_algorithm(a.algorithm);
  if (!algorithm)
    throw UsageError("--algorithm must be " + alternatives_text(kTrackingAlgorithms) + ", got '" + a.algorithm + "'");
  auto tracker = make_tracker(*algorithm, space, table, file.table);

  std::ofstream csv;
  if (!a.out.empty()) {
    csv.open(a.out);
    if (!csv) throw RuntimeFailure(a.out + ": cannot open for writing");
    csv << harness::tracking_csv_header() << '\n';
  }
  double max_m = 0.0, max_rad = 0.0, head_m = 0.0, head_rad = 0.0, table_m = 0.0, table_rad = 0.0;
  std::size_t lost = 0, over_centre = 0;
  for (const auto& s : file.samples) {
    const TrackingOutput& o = tracker->update(s.frame);
    for (const auto& c : o.coherence) {
      if (!c.measured) continue;
      max_m = std::max(max_m, c.error_m);
      max_rad = std::max(max_rad, c.error_rad);
      head_m = std::max(head_m, c.head_frame_m);
      head_rad = std::max(head_rad, c.head_frame_rad);
      table_m = std::max(table_m, c.table_frame_m);
      table_rad = std::max(table_rad, c.table_frame_rad);
    }
    for (bool t : o.tracked) lost += t ? 0 : 1;
    over_centre += o.state.head_over_centre ? 1 : 0;
    if (csv.is_open()) harness::write_tracking_csv_row(csv, s.t_ns, o);
  }
  if (csv.is_open()) {
    csv.close();
    if (!csv) throw RuntimeFailure(a.out + ": write failed");
  }
  const TrackingState& st = tracker->output().state;
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["radius_m"] = table.radius_m;
  doc["sides"] = table.sides;
  doc["virtual_edge_m"] = table.edge_m;
  doc["algorithm"] = std::string(to_string(*algorithm));
  doc["frames"] = file.samples.size();
  doc["physical_edge"] = st.physical_edge;
  doc["virtual_edge"] = st.virtual_edge;
  doc["physical_laps"] = st.physical_laps;
  doc["virtual_laps"] = st.virtual_laps;
  doc["max_coherence_error_m"] = max_m;
  doc["max_coherence_error_rad"] = max_rad;
  doc["max_head_frame_error_m"] = head_m;
  doc["max_head_frame_error_rad"] = head_rad;
  doc["max_table_frame_error_m"] = table_m;
  doc["max_table_frame_error_rad"] = table_rad;
  doc["untracked_device_frames"] = lost;
  doc["head_over_centre_frames"] = over_centre;
  if (!a.out.empty()) doc["out"] = a.out;
  print_result(doc, a.json);
}

// ---- curvlab inspect vergence / stick -----------------------------------

struct VergenceArgs {
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 1.0;
  double ipd_m = 0.063;
  double distance_m = 1.0;
  bool json = false;
};

void check_distance(const Space& space, double d_m, const std::string& option) {
  require_positive(d_m, option, "metres");
  if (space.kind == SpaceKind::S3 && d_m >= kPi * space.radius_m)
    throw UsageError(option + " must be below ρπ = " + std::to_string(kPi * space.radius_m) +
                     " m in S3 (farther points are seen through the antipode)");
}

Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

void run_vergence(const VergenceArgs& a) {
  require_positive(a.radius_m, "--radius-m", "metres");
  require_positive(a.ipd_m, "--ipd-m", "metres");
  const Space space{a.kind, a.radius_m};
  check_distance(space, a.distance_m, "--distance-m");
  const VergenceReading r = vergence_straight_ahead(space, a.ipd_m, a.distance_m);
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["radius_m"] = a.radius_m;
  doc["ipd_m"] = a.ipd_m;
  doc["distance_m"] = a.distance_m;
  doc["vergence_deg"] = r.vergence_rad * 180.0 / kPi;
  doc["tourist_distance_m"] = finite_or_null(r.tourist_distance_m);
  doc["native_distance_m"] = r.native_distance_m;
  print_result(doc, a.json);
}

struct StickArgs {
  SpaceKind kind = SpaceKind::E3;
  double radius_m = 1.0;
  double length_m = 1.0;
  double distance_m = 1.0;
  double ipd_m = 0.063;
  std::string view = "native";
  double bend_m = 0.0;
  bool json = false;
};

void run_stick(const StickArgs& a) {
  require_positive(a.radius_m, "--radius-m", "metres");
  require_positive(a.length_m, "--length-m", "metres");
  require_positive(a.ipd_m, "--ipd-m", "metres");
  require_finite(a.bend_m, "--bend-m");
  const Space space{a.kind, a.radius_m};
  check_distance(space, a.distance_m, "--distance-m");
  if (a.kind == SpaceKind::S3 && a.length_m >= kPi * a.radius_m)
    throw UsageError("--length-m must be below ρπ in S3");
  if (std::abs(a.bend_m) >= a.distance_m)
    throw UsageError("--bend-m must be smaller in size than --distance-m");
  BentStick stick;
  stick.length_m = a.length_m;
  stick.sagitta_m = a.bend_m;
  const auto view = parse_view_preset(a.view);
  if (!view) throw UsageError("--view must be " + alternatives_text(binocular_views()) + ", got '" + a.view + "'");
  const StickPerception p = perceive_stick(space, stick, a.distance_m, eyes_from_ipd(a.ipd_m), *view);
  Json doc;
  doc["space"] = std::string(to_string(a.kind));
  doc["radius_m"] = a.radius_m;
  doc["view"] = a.view;
  doc["length_m"] = a.length_m;
  doc["distance_m"] = a.distance_m;
  doc["bend_m"] = a.bend_m;
  doc["distances_m"] = Json::array();
  for (double d : p.distances_m) doc["distances_m"].push_back(d);
  doc["perceived_sagitta_m"] = p.perceived_sagitta_m;
  print_result(doc, a.json);
}

}  // namespace

void add_track_commands(CLI::App& app) {
  {
    auto* group = app.add_subcommand(
        "trajectory", "write a scripted lab trajectory of head and hands around the table (CSV)");
    group->require_subcommand(1);
    const std::pair<const char*, const char*> kinds[] = {
        {"walk-around", "the head circles the table, hands resting on the rail"},
        {"head-square", "the paper's head-square: head moves d forward, left, back, right; hands still"},
        {"hand-lap", "head still, the right hand runs round the rail"},
        {"lean-over-center", "the head leans across the table centre and back"}};
    for (const auto& [name, help] : kinds) {
      auto args = std::make_shared<TrajectoryArgs>();
      auto* cmd = group->add_subcommand(name, help);
      add_common_trajectory_options(cmd, args.get());
      const std::string kind = name;
      if (kind == "walk-around" || kind == "hand-lap") {
        auto* laps = cmd->add_option("--laps", args->laps, "laps round the table");
        if (kind == "walk-around") laps->required();
        cmd->add_option("--direction", args->direction, "ccw (default) or cw, seen from above")
            ->check(CLI::IsMember({"ccw", "cw"}));
      }
      if (kind == "head-square")
        cmd->add_option("--side-m", args->side_m, "side of the square in metres")->required();
      if (kind == "lean-over-center") {
        cmd->add_option("--overshoot-m", args->overshoot_m, "how far past the centre (default 0.20)");
        cmd->add_option("--lean-height-m", args->lean_height_m, "eye height while leaning (default 1.20)");
      }
      cmd->callback([args, kind] { run_trajectory(kind, *args); });
    }
  }
  {
    auto args = std::make_shared<TrackArgs>();
    auto* cmd = app.add_subcommand(
        "track", "run a tracking algorithm over a trajectory: virtual poses, state, coherence");
    cmd->add_option("--trajectory", args->trajectory, "trajectory CSV (docs/tracking.md)")->required();
    add_space_option(cmd, &args->kind);
    auto* radius = cmd->add_option("--radius-m", args->radius_m, "radius ρ in metres");
    auto* edge = cmd->add_option("--edge-m", args->edge_m,
                                 "virtual table edge in metres (default: the physical table's)");
    radius->excludes(edge);
    cmd->add_option("--sides", args->sides, "virtual table sides (S3 3, E3 4, H3 ≥ 5; default per space)")
        ->check(CLI::Range(3, 1000));
    cmd->add_option("--algorithm", args->algorithm, alternatives_text(kTrackingAlgorithms))
        ->required()
        ->check(CLI::IsMember(member_names(names_of(kTrackingAlgorithms))));
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->add_option("--out", args->out, "per-frame CSV of virtual poses and state");
    cmd->callback([args, radius, edge] { run_track(*args, radius->count() > 0, edge->count() > 0); });
  }
  auto* inspect = app.get_subcommand("inspect");
  {
    auto args = std::make_shared<VergenceArgs>();
    auto* cmd = inspect->add_subcommand(
        "vergence", "vergence toward a point straight ahead and the distances a Euclidean observer reads");
    add_space_option(cmd, &args->kind);
    cmd->add_option("--radius-m", args->radius_m, "radius ρ in metres")->required();
    cmd->add_option("--ipd-m", args->ipd_m, "interpupillary distance (default 0.063)");
    cmd->add_option("--distance-m", args->distance_m, "geodesic distance of the point")->required();
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->callback([args] { run_vergence(*args); });
  }
  {
    auto args = std::make_shared<StickArgs>();
    auto* cmd = inspect->add_subcommand(
        "stick", "how a Euclidean observer perceives a horizontal stick straight ahead");
    add_space_option(cmd, &args->kind);
    cmd->add_option("--radius-m", args->radius_m, "radius ρ in metres")->required();
    cmd->add_option("--length-m", args->length_m, "stick length")->required();
    cmd->add_option("--distance-m", args->distance_m, "geodesic distance of its midpoint")->required();
    cmd->add_option("--ipd-m", args->ipd_m, "interpupillary distance (default 0.063)");
    cmd->add_option("--view", args->view, alternatives_text(binocular_views()))
        ->required()
        ->check(CLI::IsMember(member_names(binocular_views())));
    cmd->add_option("--bend-m", args->bend_m, "signed bend (sagitta), positive toward the viewer");
    cmd->add_flag("--json", args->json, "print JSON");
    cmd->callback([args] { run_stick(*args); });
  }
}

}  // namespace curvlab::harness::cli
