// A shot on a curved table as data: the table, the balls at rest, the cue's
// input, and what happened (docs/billiards.md). The same JSON is what
// `curvlab billiards shot` reads and writes and what a play block stores, so
// any stored shot can be simulated again from its inputs.
#pragma once

#include "curvlab/geometry/billiards.hpp"
#include "curvlab/harness/result.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::billiards {

namespace phys = curvlab::geometry::billiards;
using Json = nlohmann::ordered_json;

struct TableSpec {
  geometry::SpaceKind space = geometry::SpaceKind::E3;
  double edge_m = 1.0;
  int sides = 0;  // 0: the space's right-angled default (3, 4, 5)
};

// A right-angled table's cloth; a bad_input error for an impossible table.
Result<phys::Cloth> make_table(const TableSpec& spec);

struct BallPlace {
  std::string id;
  phys::Vec2 native_m{0.0};
  bool pocketed = false;
  int pocket = -1;
};

// The cue's input. The ball leaves along the geodesic toward `toward_m`
// (native coordinates) either at `speed_m_s` (rolling or sliding), or
// through the cue model from `cue_speed_m_s` and the tip's offset.
struct ShotSpec {
  std::string ball;
  phys::Vec2 toward_m{0.0};
  std::optional<double> speed_m_s;
  bool rolling = true;
  std::optional<double> cue_speed_m_s;
  phys::Vec2 tip{0.0};  // side (right), height (up): fractions of R
};

struct ShotInput {
  std::vector<BallPlace> balls;
  std::optional<ShotSpec> shot;
};

// Reads a state file's JSON ({"balls": [...], "shot": {...}}). Every
// problem names its field: a ball off the table or overlapping another, an
// unknown ball, a speed that is not a finite positive number.
Result<ShotInput> parse_shot_input(const std::string& text, const std::string& source,
                                   const phys::Cloth& cloth, const phys::Parameters& params);

struct BallState {
  std::string id;
  phys::Vec2 native_m{0.0};
  double speed_m_s = 0.0;
  bool pocketed = false;
  int pocket = -1;
};

struct EventRecord {
  phys::Event event;
  std::vector<BallState> after;  // the balls involved, just after
};

// A shot stops after this many events wherever its balls are (a cluster of
// touching balls trading ever smaller bounces never comes to rest in a
// finite number of events); ShotOutcome::event_limit says so.
inline constexpr std::size_t kMaxShotEvents = 20000;

struct ShotOutcome {
  bool miscue = false;
  bool event_limit = false;  // stopped at kMaxShotEvents events
  std::vector<EventRecord> events;
  std::vector<BallState> final;
  phys::Invariants invariants;
  double end_s = 0.0;
  bool all_still = true;
};

// The physics system for balls at rest (frames transported from the table's
// centre).
phys::System at_rest(const phys::Cloth& cloth, const phys::Parameters& params,
                     const std::vector<BallPlace>& balls);
// The cue ball's velocity and spin for a shot (a miscue gives none).
phys::Strike strike_for(const phys::System& system, const phys::Parameters& params, std::size_t ball,
                        const ShotSpec& shot);
// Simulates the shot until every ball is still or pocketed, or until_s.
ShotOutcome simulate(const phys::Cloth& cloth, const phys::Parameters& params,
                     const std::vector<BallPlace>& balls, const ShotSpec& shot, double until_s);

BallState ball_state(const phys::System& system, const std::vector<BallPlace>& balls, std::size_t i);

Json to_json(const phys::Parameters& params);
Json to_json(const std::vector<BallPlace>& balls);
Json to_json(const ShotSpec& shot);
Json to_json(const ShotOutcome& outcome, const std::vector<BallPlace>& balls);
// The rest state after a shot, as balls for the next one.
std::vector<BallPlace> rest_state(const ShotOutcome& outcome);

}  // namespace curvlab::harness::billiards
