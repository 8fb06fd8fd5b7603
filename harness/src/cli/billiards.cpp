// `curvlab billiards shot` and `curvlab billiards rack`: the curved-table
// physics from the command line, for checking it and for scripts
// (docs/billiards.md).
#include "common.hpp"

#include "curvlab/harness/billiards/shot.hpp"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>

namespace curvlab::harness::cli {
namespace {

namespace bl = curvlab::harness::billiards;
namespace phys = curvlab::geometry::billiards;

struct TableArgs {
  geometry::SpaceKind space = geometry::SpaceKind::E3;
  double edge_m = 1.0;
  int sides = 0;
  std::vector<std::string> set;
};

void add_table_options(CLI::App* cmd, TableArgs* a) {
  add_space_option(cmd, &a->space);
  cmd->add_option("--edge-m", a->edge_m, "table edge in metres (default 1.0)");
  cmd->add_option("--sides", a->sides, "table sides (default: 3 in S3, 4 in E3, 5 in H3)");
  cmd->add_option("--set", a->set, "NAME=VALUE: a physics parameter (repeatable; docs/billiards.md)");
}

phys::Parameters parameters(const TableArgs& a) {
  phys::Parameters p;
  for (const auto& item : a.set) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw UsageError("--set " + item + ": expected NAME=VALUE");
    const std::string name = item.substr(0, eq);
    const std::string text = item.substr(eq + 1);
    std::size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || text.empty())
      throw UsageError("--set " + item + ": expected a number after '=', found \"" + text + "\"");
    if (auto e = phys::set_parameter(p, name, value)) throw UsageError("--set: " + *e);
  }
  return p;
}

phys::Cloth table(const TableArgs& a) {
  if (!(a.edge_m > 0.0) || !std::isfinite(a.edge_m)) throw UsageError("--edge-m must be a positive number of metres");
  auto cloth = bl::make_table({a.space, a.edge_m, a.sides});
  if (!cloth) throw UsageError(cloth.error().message);
  return std::move(cloth).value();
}

Json header(const TableArgs& a, const phys::Cloth& c, const phys::Parameters& p) {
  return Json{{"space", std::string(geometry::to_string(a.space))},
              {"radius_m", c.radius_m},
              {"sides", c.table.sides},
              {"edge_m", c.table.edge_m},
              {"apothem_m", c.table.apothem_m()},
              {"parameters", bl::to_json(p)}};
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UsageError(path + ": cannot open the state file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void print_human(const Json& doc) {
  std::printf("%s table, %d sides, edge %.3f m, radius %.4f m\n", doc["space"].get<std::string>().c_str(),
              doc["sides"].get<int>(), doc["edge_m"].get<double>(), doc["radius_m"].get<double>());
  if (doc.contains("miscue") && doc["miscue"].get<bool>()) std::printf("miscue: the tip slipped off the ball\n");
  if (doc.contains("events")) {
    std::printf("%10s  %-9s  %s\n", "t (s)", "event", "balls");
    for (const auto& e : doc["events"]) {
      std::string balls;
      for (const auto& b : e["balls"]) balls += (balls.empty() ? "" : ", ") + b.get<std::string>();
      if (e.contains("cushion")) balls += "  cushion " + std::to_string(e["cushion"].get<int>());
      if (e.contains("pocket")) balls += "  pocket " + std::to_string(e["pocket"].get<int>());
      std::printf("%10.6f  %-9s  %s\n", e["t_s"].get<double>(), e["kind"].get<std::string>().c_str(), balls.c_str());
    }
  }
  const Json& balls = doc.contains("final") ? doc["final"] : doc["balls"];
  std::printf("%-6s %10s %10s  %s\n", "ball", "x (m)", "z (m)", "");
  for (const auto& b : balls)
    std::printf("%-6s %10.6f %10.6f  %s\n", b["id"].get<std::string>().c_str(), b["x_m"].get<double>(),
                b["z_m"].get<double>(), b.value("pocketed", false) ? ("pocket " + std::to_string(b.value("pocket", -1))).c_str() : "");
  if (doc.contains("invariants"))
    std::printf("invariants: off surface %.2e (relative), overlap %.2e m, energy change %.3e (relative)\n",
                doc["invariants"]["max_off_surface_rel"].get<double>(), doc["invariants"]["max_overlap_m"].get<double>(),
                doc["invariants"]["energy_change_rel"].get<double>());
}

struct ShotArgs {
  TableArgs table;
  std::string state;
  double until_s = 120.0;
  bool json = false;
};

void run_shot(const ShotArgs& a) {
  const phys::Parameters p = parameters(a.table);
  const phys::Cloth c = table(a.table);
  if (!(a.until_s > 0.0) || !std::isfinite(a.until_s)) throw UsageError("--until-s must be a positive number of seconds");
  auto input = bl::parse_shot_input(read_file(a.state), a.state, c, p);
  if (!input) raise(input.error());
  if (!input->shot) throw UsageError(a.state + ": shot: missing: expected {\"ball\", \"toward_m\", ...}");
  const bl::ShotOutcome outcome = bl::simulate(c, p, input->balls, *input->shot, a.until_s);
  Json doc = header(a.table, c, p);
  doc.update(bl::to_json(outcome, input->balls));
  if (a.json)
    std::cout << doc.dump(2) << '\n';
  else
    print_human(doc);
}

struct RackArgs {
  TableArgs table;
  int balls = 15;
  bool json = false;
};

void run_rack(const RackArgs& a) {
  const phys::Parameters p = parameters(a.table);
  const phys::Cloth c = table(a.table);
  auto r = phys::rack(c, p, a.balls);
  if (const auto* e = std::get_if<geometry::GeometryError>(&r)) throw UsageError(e->message);
  std::vector<bl::BallPlace> places;
  for (const auto& b : std::get<std::vector<phys::RackBall>>(r)) places.push_back({b.id, b.native_m, false, -1});
  Json doc = header(a.table, c, p);
  doc["balls"] = bl::to_json(places);
  if (a.json)
    std::cout << doc.dump(2) << '\n';
  else
    print_human(doc);
}

}  // namespace

void add_billiards_commands(CLI::App& app) {
  auto* group = app.add_subcommand("billiards", "Billiards physics on a curved table: one shot, or a rack");
  group->require_subcommand(1);

  auto shot_args = std::make_shared<ShotArgs>();
  auto* shot = group->add_subcommand("shot", "Simulate one shot from a state file and print its events");
  add_table_options(shot, &shot_args->table);
  shot->add_option("--state", shot_args->state, "JSON file: balls and the shot (docs/billiards.md)")->required();
  shot->add_option("--until-s", shot_args->until_s, "stop after this many simulated seconds (default 120)");
  shot->add_flag("--json", shot_args->json, "print JSON");
  shot->callback([shot_args] { run_shot(*shot_args); });

  auto rack_args = std::make_shared<RackArgs>();
  auto* rack = group->add_subcommand("rack", "Print a standard rack fitted to the table, as a state file");
  add_table_options(rack, &rack_args->table);
  rack->add_option("--balls", rack_args->balls, "object balls, 0 to 15 (default 15)");
  rack->add_flag("--json", rack_args->json, "print JSON");
  rack->callback([rack_args] { run_rack(*rack_args); });
}

}  // namespace curvlab::harness::cli
