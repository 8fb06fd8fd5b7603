// `curvlab billiards shot` and `curvlab billiards rack` as a script meets
// them (docs/billiards.md): the documented JSON keys, a rolling ball's stop
// point checked against an independent geodesic, bad input refused with exit
// code 2 and the field named, and a rack fed back as a shot's state file.
#include "run_cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>
#include <unistd.h>

namespace curvlab::testing {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

constexpr std::array kSpaces{"S3", "E3", "H3"};
// Every physics parameter, as docs/billiards.md lists them.
constexpr std::array kParameters{"radius_m",         "mass_kg",         "mu_slide",         "mu_roll",
                                 "mu_spin",          "restitution_ball", "restitution_cushion",
                                 "friction_ball",    "friction_cushion", "g_m_s2",
                                 "pocket_radius_m",  "cue_mass_kg",     "miscue_fraction"};

// A state file in the temporary folder, removed when the test ends.
class StateFile {
 public:
  explicit StateFile(const std::string& text) {
    static int serial = 0;
    path_ = fs::temp_directory_path() /
            ("curvlab-billiards-" + std::to_string(::getpid()) + "-" + std::to_string(serial++) + ".json");
    std::ofstream(path_) << text;
  }
  StateFile(const StateFile&) = delete;
  StateFile& operator=(const StateFile&) = delete;
  ~StateFile() {
    std::error_code ignored;
    fs::remove(path_, ignored);
  }
  [[nodiscard]] std::string path() const { return path_.string(); }

 private:
  fs::path path_;
};

json parse_or_fail(const CliResult& r) {
  try {
    return json::parse(r.out);
  } catch (const json::exception& e) {
    ADD_FAILURE() << "output is not one JSON document (" << e.what() << "):\n" << r.out;
    return json::object();
  }
}

json shot_json(const std::string& space, const json& state, const std::string& extra = "") {
  const StateFile file(state.dump());
  const CliResult r = run_cli("billiards shot --space " + space + " --state '" + file.path() + "' --json " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  return parse_or_fail(r);
}

// ---- the output's keys ---------------------------------------------------

TEST(BilliardsShot, JsonHasEveryDocumentedKeyAndEventsInTimeOrder) {
  // A cue ball driven into an object ball near cushion 0 in E3: ball,
  // cushion, rolling and stop events.
  const json state = {{"balls",
                       {{{"id", "cue"}, {"x_m", 0.0}, {"z_m", -0.1}},
                        {{"id", "7"}, {"x_m", 0.0}, {"z_m", 0.3}},
                        {{"id", "8"}, {"x_m", 0.38}, {"z_m", 0.38}}}},
                      {"shot", {{"ball", "cue"}, {"toward_m", {0.0, 0.3}}, {"speed_m_s", 3.0}}}};
  const json doc = shot_json("E3", state);
  for (const char* key : {"space", "radius_m", "sides", "edge_m", "apothem_m", "parameters", "miscue", "events",
                          "final", "end_s", "all_still", "invariants"})
    EXPECT_TRUE(doc.contains(key)) << key;
  EXPECT_EQ(doc["space"], "E3");
  EXPECT_EQ(doc["sides"], 4);
  EXPECT_NEAR(doc["edge_m"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(doc["apothem_m"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(doc["radius_m"].get<double>(), 1.0, 0.0);
  ASSERT_TRUE(doc["parameters"].is_object());
  EXPECT_EQ(doc["parameters"].size(), kParameters.size());
  for (const char* name : kParameters) EXPECT_TRUE(doc["parameters"].contains(name)) << name;
  EXPECT_NEAR(doc["parameters"]["mu_roll"].get<double>(), 0.01, 0.0);

  ASSERT_TRUE(doc["events"].is_array());
  ASSERT_GE(doc["events"].size(), 4u);
  double last_t = 0.0;
  std::set<std::string> kinds;
  for (const json& e : doc["events"]) {
    for (const char* key : {"t_s", "kind", "balls", "after"}) ASSERT_TRUE(e.contains(key)) << key << " in " << e;
    const double t = e["t_s"].get<double>();
    EXPECT_GE(t, last_t) << e;
    last_t = t;
    const std::string kind = e["kind"].get<std::string>();
    kinds.insert(kind);
    EXPECT_TRUE(kind == "ball" || kind == "cushion" || kind == "pocket" || kind == "rolling" ||
                kind == "spinning" || kind == "stop")
        << kind;
    EXPECT_EQ(e["balls"].size(), kind == "ball" ? 2u : 1u) << e;
    EXPECT_EQ(e["after"].size(), e["balls"].size()) << e;
    EXPECT_EQ(e.contains("cushion"), kind == "cushion") << e;
    EXPECT_EQ(e.contains("pocket"), kind == "pocket") << e;
    for (const json& a : e["after"])
      for (const char* key : {"id", "x_m", "z_m", "speed_m_s"}) EXPECT_TRUE(a.contains(key)) << key << " in " << e;
  }
  EXPECT_TRUE(kinds.count("ball"));
  EXPECT_TRUE(kinds.count("cushion"));
  EXPECT_TRUE(kinds.count("stop"));
  EXPECT_EQ(doc["events"][0]["kind"], "ball");
  EXPECT_EQ(doc["events"][0]["balls"], json({"cue", "7"}));

  ASSERT_EQ(doc["final"].size(), 3u);
  for (const json& b : doc["final"])
    for (const char* key : {"id", "x_m", "z_m", "speed_m_s", "pocketed"}) EXPECT_TRUE(b.contains(key)) << key;
  EXPECT_EQ(doc["final"][0]["id"], "cue");
  EXPECT_TRUE(doc["all_still"].get<bool>());
  EXPECT_GE(doc["end_s"].get<double>(), last_t);
  for (const char* key : {"max_off_surface_rel", "max_overlap_m", "energy_change_rel"})
    EXPECT_TRUE(doc["invariants"].contains(key)) << key;
  EXPECT_LT(doc["invariants"]["max_overlap_m"].get<double>(), 1e-9);
  EXPECT_LE(doc["invariants"]["energy_change_rel"].get<double>(), 0.0);
}

// ---- the stop point ------------------------------------------------------

// The cloth's 2-D space form, written here from the textbook formulas (not
// the project's): a point at native (x, z) is ρ(S(r/ρ) x/r, S(r/ρ) z/r, C(r/ρ))
// with r = |(x, z)|.
struct Form {
  int k;  // +1, 0, −1
  long double rho;
  [[nodiscard]] long double C(long double t) const { return k > 0 ? cosl(t) : k < 0 ? coshl(t) : 1.0L; }
  [[nodiscard]] long double S(long double t) const { return k > 0 ? sinl(t) : k < 0 ? sinhl(t) : t; }
  [[nodiscard]] std::array<long double, 3> point(long double x, long double z) const {
    const long double r = hypotl(x, z);
    if (r == 0) return {0, 0, rho};
    const long double s = rho * S(r / rho) / r;
    return {s * x, s * z, rho * C(r / rho)};
  }
  [[nodiscard]] long double dot(const std::array<long double, 3>& a, const std::array<long double, 3>& b) const {
    return k * (a[0] * b[0] + a[1] * b[1]) + a[2] * b[2];
  }
  // Distance along the cloth, from the invariant p·q = ρ² C(d/ρ) (E3: the plane's).
  [[nodiscard]] long double distance(const std::array<long double, 3>& a, const std::array<long double, 3>& b) const {
    if (k == 0) return hypotl(a[0] - b[0], a[1] - b[1]);
    const long double c = dot(a, b) / (rho * rho);
    return rho * (k > 0 ? acosl(std::clamp(c, -1.0L, 1.0L)) : acoshl(std::max(c, 1.0L)));
  }
  // The point s metres from a along the geodesic toward b, in native coordinates.
  [[nodiscard]] std::array<long double, 2> toward(long double ax, long double az, long double bx, long double bz,
                                                  long double s) const {
    const auto a = point(ax, az);
    const auto b = point(bx, bz);
    const long double d = distance(a, b);
    std::array<long double, 3> q{};
    for (int i = 0; i < 3; ++i) {
      // The unit tangent at a toward b: (b − C a) / (ρ S); E3: (b − a)/d.
      const long double u = k == 0 ? (b[i] - a[i]) / d : (b[i] - C(d / rho) * a[i]) / (rho * S(d / rho));
      q[i] = k == 0 ? a[i] + s * u : C(s / rho) * a[i] + rho * S(s / rho) * u;
    }
    const long double r = hypotl(q[0], q[1]);
    const long double angle =
        k == 0 ? r : k > 0 ? rho * atan2l(r, q[2]) : rho * asinhl(r / rho);
    return {angle * q[0] / r, angle * q[1] / r};
  }
};

TEST(BilliardsShot, RollingBallStopsAtVSquaredOverTwoMuRollGAlongTheGeodesicTowardItsAim) {
  // Away from the centre, aimed across it off-centre: in S3 and H3 the
  // geodesic is not the native straight line, so the check sees a path that
  // merely heads toward the aim.
  const double v = 0.5, mu_roll = 0.05, g = 9.81;
  const double stop_m = v * v / (2.0 * mu_roll * g);
  const std::array<double, 2> from{0.1, 0.1}, aim{-0.2, 0.05};
  for (const char* space : kSpaces) {
    SCOPED_TRACE(space);
    const json state = {{"balls", {{{"id", "cue"}, {"x_m", from[0]}, {"z_m", from[1]}}}},
                        {"shot", {{"ball", "cue"}, {"toward_m", {aim[0], aim[1]}}, {"speed_m_s", v}, {"motion", "rolling"}}}};
    const json doc = shot_json(space, state, "--set mu_roll=0.05 --set pocket_radius_m=0");
    ASSERT_TRUE(doc.contains("final"));
    EXPECT_EQ(doc["events"].back()["kind"], "stop");
    for (const json& e : doc["events"]) EXPECT_NE(e["kind"], "cushion") << e;
    const std::string kind = space;
    const Form form{kind == "S3" ? 1 : kind == "H3" ? -1 : 0, doc["radius_m"].get<long double>()};
    const auto expect = form.toward(from[0], from[1], aim[0], aim[1], stop_m);
    const double x = doc["final"][0]["x_m"].get<double>(), z = doc["final"][0]["z_m"].get<double>();
    EXPECT_NEAR(x, static_cast<double>(expect[0]), 1e-9);
    EXPECT_NEAR(z, static_cast<double>(expect[1]), 1e-9);
    // And the native straight line would have been visibly elsewhere in S3 and H3.
    if (kind != "E3") {
      const double len = std::hypot(aim[0] - from[0], aim[1] - from[1]);
      const double lx = from[0] + stop_m * (aim[0] - from[0]) / len, lz = from[1] + stop_m * (aim[1] - from[1]) / len;
      EXPECT_GT(std::hypot(x - lx, z - lz), 1e-4);
    }
    EXPECT_NEAR(doc["events"].back()["t_s"].get<double>(), v / (mu_roll * g), 1e-9);
  }
}

// ---- bad input -----------------------------------------------------------

// Runs a shot that must be refused: exit code 2, and every `needles` in the message.
void expect_refused(const std::string& state_text, const std::vector<std::string>& needles,
                    const std::string& extra = "", const std::string& space = "E3") {
  const StateFile file(state_text);
  const CliResult r = run_cli("billiards shot --space " + space + " --state '" + file.path() + "' --json " + extra);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  for (const auto& needle : needles) EXPECT_NE(r.out.find(needle), std::string::npos) << needle << " in:\n" << r.out;
}

std::string one_ball_shot(const std::string& shot_fields) {
  return R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0}, {"id": "1", "x_m": 0.2, "z_m": 0}],
             "shot": {"ball": "cue", "toward_m": [0.2, 0], )" +
         shot_fields + "}}";
}

TEST(BilliardsShot, BadInputExitsTwoNamingTheField) {
  // A ball whose centre is nearer than R to cushion 0 (E3: z = 0.5 is on it).
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0.49}],
                     "shot": {"ball": "cue", "toward_m": [0, 0], "speed_m_s": 1}})",
                 {"balls[0]", "off the table", "cue"});
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 2, "z_m": 0}],
                     "shot": {"ball": "cue", "toward_m": [0, 0], "speed_m_s": 1}})",
                 {"balls[0]", "off the table"});
  // Two balls closer than 2R.
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0}, {"id": "9", "x_m": 0.05, "z_m": 0}],
                     "shot": {"ball": "cue", "toward_m": [0.2, 0], "speed_m_s": 1}})",
                 {"balls[1]", "overlaps", "\"9\"", "\"cue\""});
  // Speeds: negative, zero, not finite, not a number, too fast; by cue too.
  expect_refused(one_ball_shot(R"("speed_m_s": -1)"), {"shot.speed_m_s"});
  expect_refused(one_ball_shot(R"("speed_m_s": 0)"), {"shot.speed_m_s"});
  // JSON has no infinity: a number beyond double's range is refused where it stands.
  expect_refused(one_ball_shot(R"("speed_m_s": 1e999)"), {"not valid JSON", "1e999"});
  expect_refused(one_ball_shot(R"("speed_m_s": "fast")"), {"shot.speed_m_s"});
  expect_refused(one_ball_shot(R"("speed_m_s": 25)"), {"shot.speed_m_s"});
  expect_refused(one_ball_shot(R"("cue_speed_m_s": -3, "tip": [0, 0])"), {"shot.cue_speed_m_s"});
  expect_refused(one_ball_shot(R"("speed_m_s": 1, "motion": "skidding")"), {"shot.motion"});
  // A shot ball that is not on the table's list.
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0}],
                     "shot": {"ball": "ghost", "toward_m": [0.2, 0], "speed_m_s": 1}})",
                 {"shot.ball", "ghost"});
  // Malformed JSON, and JSON of the wrong shape.
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0}], "shot": )", {"(file)", "not valid JSON", "line 1"});
  expect_refused(R"([1, 2, 3])", {"expected a JSON object"});
  expect_refused(R"({"balls": []})", {"balls"});
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0}], "shot": {}})", {"balls[0].z_m"});
  expect_refused(R"({"balls": [{"id": "cue", "x_m": 0, "z_m": 0}]})", {"shot", "missing"});
  // An unknown parameter, and a known one out of its range or not a number.
  const std::string good = one_ball_shot(R"("speed_m_s": 1)");
  expect_refused(good, {"mu_rol", "unknown billiards parameter"}, "--set mu_rol=0.1");
  expect_refused(good, {"restitution_ball", "out of range"}, "--set restitution_ball=1.5");
  expect_refused(good, {"mu_roll", "expected a number"}, "--set mu_roll=abc");
  expect_refused(good, {"NAME=VALUE"}, "--set mu_roll");
}

TEST(BilliardsShot, TheGoodStateFileOfTheBadInputTestIsAccepted) {
  // So that the refusals above are about the one field each changes.
  for (const char* space : kSpaces) {
    const json doc = shot_json(space, json::parse(one_ball_shot(R"("speed_m_s": 1)")));
    EXPECT_FALSE(doc["events"].empty());
  }
}

// ---- parameters ----------------------------------------------------------

TEST(BilliardsShot, SetAcceptsEveryParameterNameAndEchoesTheValue) {
  const json state = json::parse(one_ball_shot(R"("speed_m_s": 1)"));
  const json defaults = shot_json("E3", state)["parameters"];
  for (const char* name : kParameters) {
    SCOPED_TRACE(name);
    ASSERT_TRUE(defaults.contains(name));
    const double value = 0.9 * defaults[name].get<double>();
    char arg[96];
    std::snprintf(arg, sizeof arg, "--set %s=%.17g", name, value);
    const json doc = shot_json("E3", state, arg);
    ASSERT_TRUE(doc.contains("parameters"));
    EXPECT_EQ(doc["parameters"][name].get<double>(), value);
    for (const char* other : kParameters) {
      if (std::string(other) != name) {
        EXPECT_EQ(doc["parameters"][other], defaults[other]) << other;
      }
    }
  }
}

// ---- rack into shot ------------------------------------------------------

TEST(BilliardsRack, RackOutputWithAShotAddedIsAStateFileForShot) {
  for (const char* space : kSpaces) {
    SCOPED_TRACE(space);
    const CliResult r = run_cli(std::string("billiards rack --space ") + space + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    json rack = parse_or_fail(r);
    ASSERT_EQ(rack["balls"].size(), 16u);
    EXPECT_EQ(rack["balls"][0]["id"], "cue");
    EXPECT_EQ(rack["space"], space);
    const json apex = rack["balls"][1];
    rack["shot"] = {{"ball", "cue"},
                    {"toward_m", {apex["x_m"], apex["z_m"]}},
                    {"cue_speed_m_s", 8.0},
                    {"tip", {0.0, 0.1}}};
    const json doc = shot_json(space, rack);
    ASSERT_TRUE(doc.contains("events"));
    ASSERT_FALSE(doc["events"].empty());
    EXPECT_EQ(doc["events"][0]["kind"], "ball");
    EXPECT_EQ(doc["events"][0]["balls"], json({"cue", "1"}));
    EXPECT_GT(doc["events"].size(), 30u);
    EXPECT_EQ(doc["final"].size(), 16u);
    EXPECT_TRUE(doc["all_still"].get<bool>());
    EXPECT_LT(doc["invariants"]["max_overlap_m"].get<double>(), 1e-9);
    EXPECT_LT(doc["invariants"]["max_off_surface_rel"].get<double>(), 1e-12);

    // The rest state (final, pocketed balls included) is again a state file.
    json next = {{"balls", json::array()}};
    for (const json& b : doc["final"]) {
      json place = {{"id", b["id"]}, {"x_m", b["x_m"]}, {"z_m", b["z_m"]}};
      if (b["pocketed"].get<bool>()) {
        place["pocketed"] = true;
        place["pocket"] = b["pocket"];
      }
      next["balls"].push_back(place);
    }
    if (!doc["final"][0]["pocketed"].get<bool>()) {
      next["shot"] = {{"ball", "cue"}, {"toward_m", {0.0, 0.0}}, {"speed_m_s", 1.0}};
      if (std::hypot(doc["final"][0]["x_m"].get<double>(), doc["final"][0]["z_m"].get<double>()) < 1e-6)
        next["shot"]["toward_m"] = {0.1, 0.0};
      EXPECT_FALSE(shot_json(space, next)["events"].empty());
    }
  }
}

}  // namespace
}  // namespace curvlab::testing
