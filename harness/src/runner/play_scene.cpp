#include "play_scene.hpp"

#include "curvlab/renderer/colour.hpp"

#include <array>

namespace curvlab::harness::runner {

namespace {

namespace bl = curvlab::harness::billiards;
using Json = nlohmann::ordered_json;

glm::vec4 ball_colour(std::size_t i) {
  if (i == 0) return renderer::display(0.95f, 0.95f, 0.92f);
  static const std::array<glm::vec3, 8> kColours{{{0.95f, 0.78f, 0.10f},
                                                  {0.10f, 0.25f, 0.75f},
                                                  {0.85f, 0.12f, 0.10f},
                                                  {0.45f, 0.15f, 0.55f},
                                                  {0.95f, 0.45f, 0.05f},
                                                  {0.10f, 0.50f, 0.20f},
                                                  {0.50f, 0.12f, 0.10f},
                                                  {0.05f, 0.05f, 0.05f}}};
  const glm::vec3 c = kColours[(i - 1) % kColours.size()];
  return renderer::display(c.x, c.y, c.z);
}

geometry::Isometry pose_of(const geometry::Space& space, double radius_m, const phys::Ball& b) {
  const geometry::Isometry turn = geometry::rotation(glm::mat3_cast(b.orientation));
  return phys::to_isometry(b.frame) * geometry::translation_m(space, {0.0, radius_m, 0.0}) * turn;
}

std::vector<bl::BallPlace> places(const Json& balls) {
  std::vector<bl::BallPlace> out;
  for (const auto& b : balls)
    out.push_back({b["id"].get<std::string>(), {b["x_m"].get<double>(), b["z_m"].get<double>()},
                   b.value("pocketed", false), b.value("pocket", -1)});
  return out;
}

}  // namespace

PlayScene::PlayScene(renderer::Scene& scene, const World& world, const phys::Parameters& params, std::size_t balls)
    : space_(world.space), radius_m_(params.radius_m) {
  table_ = scene.add(renderer::table_object(world.space, world.table));
  for (std::size_t i = 0; i < balls; ++i)
    balls_.push_back(scene.add(renderer::ball_object(world.space, params.radius_m, ball_colour(i), {},
                                                     i == 0 ? renderer::display(0.80f, 0.10f, 0.10f)
                                                            : renderer::display(0.96f, 0.96f, 0.92f))));
}

void PlayScene::show(renderer::Scene& scene, const phys::System& system, double t_s) const {
  if (!scene.objects()[table_].visible) scene.edit(table_).visible = true;
  for (std::size_t i = 0; i < balls_.size() && i < system.size(); ++i) {
    const phys::Ball b = system.ball_at(i, std::max(t_s, system.time_s()));
    const bool visible = b.motion != phys::Motion::pocketed;
    const geometry::Isometry pose = pose_of(space_, radius_m_, b);
    const auto& o = scene.objects()[balls_[i]];
    if (o.visible != visible || o.pose.m != pose.m) {
      auto& e = scene.edit(balls_[i]);
      e.visible = visible;
      e.pose = pose;
    }
  }
}

void PlayScene::hide(renderer::Scene& scene) const {
  scene.edit(table_).visible = false;
  for (const auto i : balls_) scene.edit(i).visible = false;
}

Result<PlayState> play_state_at(const World& world, const std::vector<data::ShotRecord>& shots, std::int64_t t_ns) {
  PlayState out;
  out.cloth = phys::make_cloth(world.space, world.table);
  if (shots.empty()) return out;
  // The shot under way at t_ns, or the last one before it.
  const data::ShotRecord* shot = &shots.front();
  for (const auto& s : shots)
    if (s.t_ns <= t_ns) shot = &s;
  const Json settings = Json::parse(shot->table_settings, nullptr, false);
  if (settings.is_discarded() || !settings.contains("parameters"))
    return Error{Error::Kind::corrupt, "shot " + std::to_string(shot->shot_index) + ": table_settings is not the "
                                       "JSON curvlab stores"};
  for (const auto& [name, value] : settings["parameters"].items())
    (void)phys::set_parameter(out.params, name, value.get<double>());
  const bool rolling = t_ns >= shot->t_ns && t_ns < shot->rest_ns;
  if (t_ns < shot->t_ns || rolling) {
    out.balls = places(Json::parse(shot->before_state)["balls"]);
  } else {
    out.balls = places(Json::parse(shot->rest_state));
  }
  out.system = bl::at_rest(out.cloth, out.params, out.balls);
  if (rolling) {
    bl::ShotSpec spec;
    const Json j = Json::parse(shot->shot);
    spec.ball = j["ball"].get<std::string>();
    spec.toward_m = {j["toward_m"][0].get<double>(), j["toward_m"][1].get<double>()};
    if (j.contains("cue_speed_m_s")) {
      spec.cue_speed_m_s = j["cue_speed_m_s"].get<double>();
      spec.tip = {j["tip"][0].get<double>(), j["tip"][1].get<double>()};
    } else {
      spec.speed_m_s = j["speed_m_s"].get<double>();
      const auto motion = j.find("motion");
      spec.rolling = motion == j.end() || *motion == Json("rolling");
    }
    std::size_t cue = 0;
    while (cue < out.balls.size() && out.balls[cue].id != spec.ball) ++cue;
    const phys::Strike strike = bl::strike_for(*out.system, out.params, cue, spec);
    if (!strike.miscue) out.system->set_motion(cue, strike.v, strike.w);
    out.t_s = static_cast<double>(t_ns - shot->t_ns) * 1e-9;
    while (out.system->next_event(out.t_s)) {
    }
  }
  return out;
}

}  // namespace curvlab::harness::runner
