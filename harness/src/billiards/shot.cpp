#include "curvlab/harness/billiards/shot.hpp"

#include <cmath>
#include <set>

namespace curvlab::harness::billiards {
namespace {

Error bad(const std::string& source, const std::string& field, const std::string& message) {
  return Error{Error::Kind::bad_input, source + ": " + field + ": " + message};
}

// A finite number at obj[key], or an error naming field.key.
std::optional<std::string> number(const Json& obj, const char* key, const std::string& field,
                                  double& out) {
  const auto it = obj.find(key);
  if (it == obj.end()) return field + "." + key + ": missing: expected a number";
  if (!it->is_number()) return field + "." + key + ": expected a number, found " + it->dump();
  out = it->get<double>();
  if (!std::isfinite(out)) return field + "." + key + ": expected a finite number";
  return std::nullopt;
}

std::optional<std::string> pair(const Json& obj, const char* key, const std::string& field,
                                phys::Vec2& out) {
  const auto it = obj.find(key);
  if (it == obj.end()) return field + "." + key + ": missing: expected [x, z]";
  if (!it->is_array() || it->size() != 2 || !(*it)[0].is_number() || !(*it)[1].is_number())
    return field + "." + key + ": expected two numbers [x, z], found " + it->dump();
  out = {(*it)[0].get<double>(), (*it)[1].get<double>()};
  if (!std::isfinite(out.x) || !std::isfinite(out.y))
    return field + "." + key + ": expected finite numbers";
  return std::nullopt;
}

}  // namespace

Result<phys::Cloth> make_table(const TableSpec& spec) {
  const int sides = spec.sides > 0 ? spec.sides : geometry::default_table_sides(spec.space);
  auto shape = geometry::right_angled_table_from_edge(spec.space, spec.edge_m, sides, 1.0);
  if (const auto* e = std::get_if<geometry::GeometryError>(&shape))
    return Error{Error::Kind::usage, e->message};
  const auto& t = std::get<geometry::TableShape>(shape);
  return phys::make_cloth(geometry::Space{spec.space, t.radius_m}, t);
}

Result<ShotInput> parse_shot_input(const std::string& text, const std::string& source,
                                   const phys::Cloth& cloth, const phys::Parameters& params) {
  Json doc;
  try {
    doc = Json::parse(text);
  } catch (const Json::exception& e) {
    // The parser's own words: the line, the column and what it read, or the
    // number too large for a double (1e999; JSON has no infinity).
    std::string why = e.what();
    if (const auto at = why.find("] "); at != std::string::npos) why = why.substr(at + 2);
    return bad(source, "(file)", "not valid JSON: " + why);
  }
  if (!doc.is_object()) return bad(source, "(file)", "expected a JSON object with \"balls\"");
  ShotInput in;
  const auto balls = doc.find("balls");
  if (balls == doc.end() || !balls->is_array() || balls->empty())
    return bad(source, "balls", "expected a non-empty array of {\"id\", \"x_m\", \"z_m\"}");
  std::set<std::string> ids;
  const double R = params.radius_m;
  for (std::size_t i = 0; i < balls->size(); ++i) {
    const Json& b = (*balls)[i];
    const std::string field = "balls[" + std::to_string(i) + "]";
    if (!b.is_object()) return bad(source, field, "expected an object");
    BallPlace place;
    const auto id = b.find("id");
    if (id == b.end() || !id->is_string() || id->get<std::string>().empty())
      return bad(source, field + ".id", "expected a non-empty string");
    place.id = id->get<std::string>();
    if (!ids.insert(place.id).second)
      return bad(source, field + ".id", "\"" + place.id + "\" names two balls");
    if (auto e = number(b, "x_m", field, place.native_m.x)) return Error{Error::Kind::bad_input, source + ": " + *e};
    if (auto e = number(b, "z_m", field, place.native_m.y)) return Error{Error::Kind::bad_input, source + ": " + *e};
    if (const auto p = b.find("pocketed"); p != b.end() && p->is_boolean()) place.pocketed = p->get<bool>();
    if (const auto p = b.find("pocket"); p != b.end() && p->is_number_integer()) place.pocket = p->get<int>();
    if (!place.pocketed) {
      const auto p = phys::from_native(cloth, place.native_m);
      for (int e = 0; e < cloth.table.sides; ++e) {
        const double d = phys::edge_distance_m(cloth, p, e);
        if (d < R - 1e-9)
          return bad(source, field, "ball \"" + place.id + "\" is off the table: its centre is " +
                                        std::to_string(d) + " m from cushion " + std::to_string(e) +
                                        ", expected at least R = " + std::to_string(R) + " m");
      }
      for (std::size_t j = 0; j < in.balls.size(); ++j) {
        if (in.balls[j].pocketed) continue;
        const double d = phys::distance_m(cloth, p, phys::from_native(cloth, in.balls[j].native_m));
        if (d < 2.0 * R - 1e-9)
          return bad(source, field, "ball \"" + place.id + "\" overlaps \"" + in.balls[j].id +
                                        "\": centres " + std::to_string(d) + " m apart, expected at least 2R = " +
                                        std::to_string(2.0 * R) + " m");
      }
    }
    in.balls.push_back(place);
  }
  const auto shot = doc.find("shot");
  if (shot == doc.end()) return in;
  if (!shot->is_object()) return bad(source, "shot", "expected an object");
  ShotSpec s;
  const auto ball = shot->find("ball");
  if (ball == shot->end() || !ball->is_string()) return bad(source, "shot.ball", "expected a ball's id");
  s.ball = ball->get<std::string>();
  if (!ids.count(s.ball)) return bad(source, "shot.ball", "no ball has the id \"" + s.ball + "\"");
  if (auto e = pair(*shot, "toward_m", "shot", s.toward_m)) return Error{Error::Kind::bad_input, source + ": " + *e};
  const bool by_speed = shot->contains("speed_m_s");
  const bool by_cue = shot->contains("cue_speed_m_s");
  if (by_speed == by_cue)
    return bad(source, "shot", "expected exactly one of \"speed_m_s\" (with \"motion\") or \"cue_speed_m_s\" (with \"tip\")");
  double speed = 0.0;
  if (by_speed) {
    if (auto e = number(*shot, "speed_m_s", "shot", speed)) return Error{Error::Kind::bad_input, source + ": " + *e};
    const auto motion = shot->find("motion");
    const std::string m = motion != shot->end() && motion->is_string() ? motion->get<std::string>() : "rolling";
    if (m != "rolling" && m != "sliding")
      return bad(source, "shot.motion", "expected \"rolling\" or \"sliding\", found \"" + m + "\"");
    s.rolling = m == "rolling";
    s.speed_m_s = speed;
  } else {
    if (auto e = number(*shot, "cue_speed_m_s", "shot", speed)) return Error{Error::Kind::bad_input, source + ": " + *e};
    s.cue_speed_m_s = speed;
    if (shot->contains("tip"))
      if (auto e = pair(*shot, "tip", "shot", s.tip)) return Error{Error::Kind::bad_input, source + ": " + *e};
  }
  if (!(speed > 0.0) || speed > 20.0)
    return bad(source, by_speed ? "shot.speed_m_s" : "shot.cue_speed_m_s",
               "expected a speed above 0 and at most 20 m/s, found " + std::to_string(speed));
  for (const auto& b : in.balls)
    if (b.id == s.ball) {
      if (b.pocketed) return bad(source, "shot.ball", "\"" + s.ball + "\" is pocketed");
      if (glm::length(b.native_m - s.toward_m) < 1e-9)
        return bad(source, "shot.toward_m", "the aim point is the ball's own position");
    }
  in.shot = s;
  return in;
}

phys::System at_rest(const phys::Cloth& cloth, const phys::Parameters& params,
                     const std::vector<BallPlace>& balls) {
  std::vector<phys::Ball> state;
  state.reserve(balls.size());
  for (const auto& b : balls) {
    phys::Ball ball;
    ball.frame = phys::frame_at(cloth, phys::from_native(cloth, b.native_m));
    if (b.pocketed) {
      ball.motion = phys::Motion::pocketed;
      ball.pocket = b.pocket;
    }
    state.push_back(ball);
  }
  return phys::System(cloth, params, std::move(state));
}

phys::Strike strike_for(const phys::System& system, const phys::Parameters& params, std::size_t ball,
                        const ShotSpec& shot) {
  const phys::Cloth& cloth = system.cloth();
  const phys::Frame f = system.ball(ball).frame;
  const phys::Vec2 aim = phys::direction_toward(cloth, f, phys::from_native(cloth, shot.toward_m));
  if (shot.cue_speed_m_s) return phys::cue_strike(params, aim, *shot.cue_speed_m_s, shot.tip);
  phys::Strike s;
  s.v = *shot.speed_m_s * aim;
  if (shot.rolling) s.w = phys::rolling_spin(params, s.v);
  return s;
}

BallState ball_state(const phys::System& system, const std::vector<BallPlace>& balls, std::size_t i) {
  const phys::Ball b = system.ball(i);
  BallState s;
  s.id = balls[i].id;
  s.native_m = phys::to_native(system.cloth(), phys::frame_position(system.cloth(), b.frame));
  s.speed_m_s = phys::speed_m_s(b);
  s.pocketed = b.motion == phys::Motion::pocketed;
  s.pocket = b.pocket;
  return s;
}

ShotOutcome simulate(const phys::Cloth& cloth, const phys::Parameters& params,
                     const std::vector<BallPlace>& balls, const ShotSpec& shot, double until_s) {
  ShotOutcome out;
  phys::System system = at_rest(cloth, params, balls);
  std::size_t cue = 0;
  while (cue < balls.size() && balls[cue].id != shot.ball) ++cue;
  const phys::Strike strike = strike_for(system, params, cue, shot);
  out.miscue = strike.miscue;
  if (!strike.miscue) system.set_motion(cue, strike.v, strike.w);
  while (true) {
    if (out.events.size() == kMaxShotEvents) {
      out.event_limit = true;
      break;
    }
    const auto e = system.next_event(until_s);
    if (!e) break;
    EventRecord r;
    r.event = *e;
    for (int who : {e->a, e->b})
      if (who >= 0) r.after.push_back(ball_state(system, balls, static_cast<std::size_t>(who)));
    out.events.push_back(std::move(r));
  }
  for (std::size_t i = 0; i < balls.size(); ++i) out.final.push_back(ball_state(system, balls, i));
  out.invariants = system.invariants();
  out.end_s = system.time_s();
  out.all_still = system.all_still();
  return out;
}

Json to_json(const phys::Parameters& params) {
  Json j = Json::object();
  for (const auto& info : phys::parameter_table()) j[std::string(info.name)] = params.*(info.field);
  return j;
}

Json to_json(const std::vector<BallPlace>& balls) {
  Json out = Json::array();
  for (const auto& b : balls) {
    Json j{{"id", b.id}, {"x_m", b.native_m.x}, {"z_m", b.native_m.y}};
    if (b.pocketed) {
      j["pocketed"] = true;
      j["pocket"] = b.pocket;
    }
    out.push_back(j);
  }
  return out;
}

Json to_json(const ShotSpec& shot) {
  Json j{{"ball", shot.ball}, {"toward_m", {shot.toward_m.x, shot.toward_m.y}}};
  if (shot.cue_speed_m_s) {
    j["cue_speed_m_s"] = *shot.cue_speed_m_s;
    j["tip"] = {shot.tip.x, shot.tip.y};
  } else {
    j["speed_m_s"] = shot.speed_m_s.value_or(0.0);
    j["motion"] = shot.rolling ? "rolling" : "sliding";
  }
  return j;
}

namespace {
Json state_json(const BallState& s, bool with_pocket) {
  Json j{{"id", s.id}, {"x_m", s.native_m.x}, {"z_m", s.native_m.y}, {"speed_m_s", s.speed_m_s}};
  if (with_pocket) {
    j["pocketed"] = s.pocketed;
    if (s.pocketed) j["pocket"] = s.pocket;
  }
  return j;
}
}  // namespace

Json to_json(const ShotOutcome& outcome, const std::vector<BallPlace>& balls) {
  Json events = Json::array();
  for (const auto& r : outcome.events) {
    Json e{{"t_s", r.event.t_s}, {"kind", std::string(phys::to_string(r.event.kind))}};
    Json ids = Json::array();
    for (int who : {r.event.a, r.event.b})
      if (who >= 0) ids.push_back(balls[static_cast<std::size_t>(who)].id);
    e["balls"] = ids;
    if (r.event.cushion >= 0) e["cushion"] = r.event.cushion;
    if (r.event.pocket >= 0) e["pocket"] = r.event.pocket;
    Json after = Json::array();
    for (const auto& s : r.after) after.push_back(state_json(s, false));
    e["after"] = after;
    events.push_back(e);
  }
  Json final = Json::array();
  for (const auto& s : outcome.final) final.push_back(state_json(s, true));
  return Json{{"miscue", outcome.miscue},
              {"events", events},
              {"final", final},
              {"end_s", outcome.end_s},
              {"all_still", outcome.all_still},
              {"event_limit", outcome.event_limit},
              {"invariants",
               {{"max_off_surface_rel", outcome.invariants.max_off_surface_rel},
                {"max_overlap_m", std::max(0.0, outcome.invariants.max_overlap_m)},
                {"energy_change_rel", outcome.invariants.energy_change_rel}}}};
}

std::vector<BallPlace> rest_state(const ShotOutcome& outcome) {
  std::vector<BallPlace> out;
  for (const auto& s : outcome.final) out.push_back({s.id, s.native_m, s.pocketed, s.pocket});
  return out;
}

}  // namespace curvlab::harness::billiards
