// The play block kind: curved-space billiards at the table between judgement
// blocks (docs/billiards.md). The block is one planned trial; each shot is
// simulated exactly at the strike (its events are what is stored), shown
// frame by frame as the balls roll, and committed in its own transaction
// when they come to rest, so a killed block resumes at the rest state after
// its last completed shot.
//
// Who shoots: the simulated player in headless runs (a seeded choice of ball
// and pocket, aimed along geodesics through the ghost ball, with human aim
// and speed noise), otherwise the participant with the cue in the right
// hand: a strike is the cue's tip reaching the cue ball, its speed and the
// tip's offset taken from the tip's motion over the last frames. On the
// desktop, holding the cue-strike key (space) and letting go strikes along
// the line of sight, harder the longer it was held.
//
// Shared (docs/shared_play.md): two stations take turns — the host shoots
// the even shots, the joiner the odd ones. The shooter's station simulates
// its shot and sends the inputs, events and rest state; the other station
// simulates the same inputs again when they arrive, compares, keeps the
// shooter's rest state, and stores the shot as its own session's.
#include "../block_kind.hpp"
#include "../play_scene.hpp"

#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/trajectory.hpp"
#include "curvlab/renderer/colour.hpp"
#include "curvlab/harness/billiards/shot.hpp"
#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/net/partner_poses.hpp"
#include "curvlab/harness/runner/shared_play.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <random>

namespace curvlab::harness::runner {

namespace {

namespace bl = curvlab::harness::billiards;
namespace events = curvlab::harness::data::events;
namespace phys = curvlab::geometry::billiards;
using Json = nlohmann::ordered_json;

constexpr double kPi = std::numbers::pi;

phys::Parameters play_parameters(const protocol::PlaySettings& play) {
  phys::Parameters p;
  for (const auto& [name, value] : play.physics) (void)phys::set_parameter(p, name, value);
  return p;
}

// The point 0.5 m from the struck ball along `aim` (its frame's
// coordinates), in native coordinates: the stored form of an aim.
phys::Vec2 toward_along(const phys::System& sys, phys::Vec2 aim) {
  const phys::Cloth& c = sys.cloth();
  const geometry::Space space = c.space();
  const phys::Frame f = sys.ball(0).frame;
  const double t = 0.5 / c.radius_m;
  return phys::to_native(c, space.C(t) * phys::frame_position(c, f) +
                                c.radius_m * space.S(t) * (f[0] * aim.x + f[1] * aim.y));
}

// The simulated player's shot: for each object ball and pocket, the ghost
// ball (2R behind the object ball on the geodesic from the pocket) and the
// cut angle at it; the smallest cut wins. Aim and speed carry noise.
bl::ShotSpec choose_shot(const phys::System& sys, const std::vector<bl::BallPlace>& balls,
                         const phys::Parameters& p, protocol::Engine& rng) {
  const phys::Cloth& c = sys.cloth();
  const geometry::Space space = c.space();
  const glm::dvec3 cue = phys::frame_position(c, sys.ball(0).frame);
  double best = 1e300;
  glm::dvec3 aim_point = phys::from_native(c, {0.0, 0.0});
  double distance = 0.5;
  for (std::size_t i = 1; i < balls.size(); ++i) {
    if (sys.ball(i).motion == phys::Motion::pocketed) continue;
    const phys::Frame of = sys.ball(i).frame;
    const glm::dvec3 ob = phys::frame_position(c, of);
    for (const glm::dvec3& pocket : c.corners) {
      // The direction at the object ball away from the pocket, and the ghost
      // ball 2R along it.
      const phys::Vec2 to_pocket = phys::direction_toward(c, of, pocket);
      const double t = 2.0 * p.radius_m / c.radius_m;
      const phys::Frame step = of * phys::Frame{1.0};
      const glm::dvec3 ghost_dir = -(step[0] * to_pocket.x + step[1] * to_pocket.y);
      const glm::dvec3 ghost = space.C(t) * ob + c.radius_m * space.S(t) * ghost_dir;
      if (phys::distance_m(c, cue, ghost) < 2.0 * p.radius_m) continue;
      // Cut angle: between cue → ghost and object → pocket at the ghost.
      const phys::Frame gf = phys::frame_at(c, ghost);
      const phys::Vec2 a = phys::direction_toward(c, gf, ob);
      const phys::Vec2 b = -phys::direction_toward(c, gf, cue);
      const double cut = std::acos(std::clamp(glm::dot(a, b), -1.0, 1.0));
      if (cut > 1.3) continue;
      const double score = cut + 0.5 * phys::distance_m(c, ob, pocket);
      if (score < best) {
        best = score;
        aim_point = ghost;
        distance = phys::distance_m(c, cue, ghost) + phys::distance_m(c, ob, pocket);
      }
    }
  }
  std::normal_distribution<double> noise(0.0, 1.0);
  bl::ShotSpec s;
  s.ball = balls[0].id;
  // Aim noise of about 1°: the aim point turned about the cue ball.
  const phys::Frame cf = sys.ball(0).frame;
  const phys::Vec2 dir = phys::direction_toward(c, cf, aim_point);
  const double turn = noise(rng) * kPi / 180.0;
  const phys::Vec2 aim{dir.x * std::cos(turn) - dir.y * std::sin(turn), dir.x * std::sin(turn) + dir.y * std::cos(turn)};
  s.toward_m = toward_along(sys, aim);
  s.cue_speed_m_s = std::clamp((1.2 + 2.2 * distance) * (1.0 + 0.08 * noise(rng)), 0.8, 7.0);
  s.tip = {0.05 * noise(rng), 0.15 + 0.1 * noise(rng)};
  return s;
}

// The participant's shot: along the head's line of sight across the cloth.
bl::ShotSpec sighted_shot(const phys::System& sys, const std::vector<bl::BallPlace>& balls,
                          const geometry::Isometry& head) {
  const phys::Cloth& c = sys.cloth();
  const geometry::Point eye = geometry::position(c.space(), head);
  const geometry::Point ahead = head * (geometry::origin(c.space()) + geometry::Vec4(0.0, 0.0, -0.3, 0.0));
  // Horizontal direction of sight, as native coordinates, from the cue ball.
  const phys::Vec2 from{eye.x, eye.z};
  const phys::Vec2 to{ahead.x, ahead.z};
  phys::Vec2 d = to - from;
  if (glm::length(d) < 1e-9) d = {0.0, -1.0};
  const phys::Vec2 cue = phys::to_native(c, phys::frame_position(c, sys.ball(0).frame));
  bl::ShotSpec s;
  s.ball = balls[0].id;
  s.toward_m = cue + 0.5 * glm::normalize(d);
  s.cue_speed_m_s = 3.0;
  s.tip = {0.0, 0.2};
  return s;
}

// The head's unwrapped azimuth about a centre, in laps, and the distance it
// walked.
class Laps {
 public:
  void add(double azimuth_rad) {
    if (last_) {
      double d = azimuth_rad - *last_;
      while (d > kPi) d -= 2.0 * kPi;
      while (d <= -kPi) d += 2.0 * kPi;
      total_rad_ += d;
    }
    last_ = azimuth_rad;
  }
  [[nodiscard]] double laps() const { return total_rad_ / (2.0 * kPi); }

 private:
  std::optional<double> last_;
  double total_rad_ = 0.0;
};

// What a play block measures frame by frame (docs/billiards.md, "Play
// figures"): laps round each table, distance walked, the hands' seen-versus-
// felt error.
struct PlayFigures {
  Laps physical, virtual_table;
  double walked_m = 0.0;
  std::optional<glm::dvec2> last_head;
  double hand_error_sum_m = 0.0;
  std::int64_t hand_error_n = 0;

  void add(const geometry::LabFrame& lab, const geometry::PhysicalTable& table,
           const geometry::TrackingOutput* tracking) {
    const auto& head = lab[geometry::Device::head];
    if (head.valid) {
      const glm::dvec2 h{head.position_m.x - table.centre_x_m, head.position_m.z - table.centre_z_m};
      physical.add(std::atan2(h.y, h.x));
      if (last_head) walked_m += glm::length(h - *last_head);
      last_head = h;
    }
    if (tracking == nullptr || !tracking->tracked[0]) return;
    const geometry::Isometry& v = tracking->pose[0];
    virtual_table.add(std::atan2(v.m[3].z, v.m[3].x));
    for (const auto& c : tracking->coherence)
      if (c.measured) {
        hand_error_sum_m += c.error_m;
        ++hand_error_n;
      }
  }
};

// The cue in the participant's right hand and both hands, drawn every frame,
// and the strike read from the cue tip's motion.
class TrackedCue {
 public:
  static constexpr double kLength_m = 1.2;
  static constexpr std::size_t kHistory = 4;

  TrackedCue(renderer::Scene& scene, const geometry::Space& space, const glm::dvec3& tip_offset_m)
      : space_(space), tip_offset_m_(tip_offset_m) {
    geometry::BentStick stick;
    stick.length_m = kLength_m;
    stick.radius_m = 0.0065;
    cue_ = scene.add(renderer::stick_object(space, stick, {}));
    for (auto& h : hands_) h = scene.add(renderer::ball_object(space, 0.04, renderer::display(0.85f, 0.66f, 0.52f), {}));
  }

  // Draws the cue and hands from this frame's curved-space poses; the tip,
  // in the cue ball's frame (metres), joins the history.
  void update(renderer::Scene& scene, const geometry::TrackingOutput& t, const geometry::Isometry& cue_ball,
              std::int64_t t_ns) {
    const geometry::Isometry& right = t.pose[2];
    const geometry::Isometry tip = right * geometry::translation_m(space_, tip_offset_m_);
    // Model chord along x, centred: turned to point along the hand's −z,
    // its front end at the tip.
    const geometry::Isometry pose = tip * geometry::rotation(glm::dvec3(0.0, 1.0, 0.0), kPi / 2.0) *
                                    geometry::translation_m(space_, {-kLength_m / 2.0, 0.0, 0.0});
    set(scene, cue_, t.tracked[2], pose);
    set(scene, hands_[0], t.tracked[1], t.pose[1]);
    set(scene, hands_[1], t.tracked[2], right);
    if (!t.tracked[2]) {
      history_.clear();
      return;
    }
    const geometry::Point p = geometry::position(space_, tip);
    const glm::dvec3 local = geometry::log_origin(space_, geometry::inverse(space_, cue_ball) * p);
    history_.push_back({t_ns, local});
    if (history_.size() > kHistory) history_.erase(history_.begin());
  }

  // A strike when the tip enters the ball this frame: the aim and the cue's
  // speed from the horizontal motion over the last frames, the tip's offset
  // at the point where it entered, across the aim (side) and above the
  // centre (height), in fractions of R.
  std::optional<bl::ShotSpec> strike(double radius_m) const {
    if (history_.size() < 2) return std::nullopt;
    const glm::dvec3 now = history_.back().local_m;
    const glm::dvec3 prev = history_[history_.size() - 2].local_m;
    if (glm::length(now) > radius_m || glm::length(prev) <= radius_m) return std::nullopt;
    const auto& then = history_.front();
    const double dt = static_cast<double>(history_.back().t_ns - then.t_ns) * 1e-9;
    if (!(dt > 0.0)) return std::nullopt;
    const glm::dvec3 v = (now - then.local_m) / dt;
    const phys::Vec2 vh{v.x, v.z};
    if (glm::length(vh) < 0.1) return std::nullopt;
    // Where the segment prev → now crosses the sphere |x| = R.
    const glm::dvec3 d = now - prev;
    const double a = glm::dot(d, d), b = 2.0 * glm::dot(prev, d), c = glm::dot(prev, prev) - radius_m * radius_m;
    const double u = (-b - std::sqrt(std::max(0.0, b * b - 4.0 * a * c))) / (2.0 * a);
    const glm::dvec3 entry = prev + std::clamp(u, 0.0, 1.0) * d;
    const phys::Vec2 aim = glm::normalize(vh);
    const phys::Vec2 right{-aim.y, aim.x};
    bl::ShotSpec s;
    s.cue_speed_m_s = std::min(glm::length(vh), 12.0);
    s.tip = {glm::dot(phys::Vec2{entry.x, entry.z}, right) / radius_m, entry.y / radius_m};
    aim_ = aim;
    return s;
  }
  [[nodiscard]] phys::Vec2 aim() const { return aim_; }

  void hide(renderer::Scene& scene) const {
    scene.edit(cue_).visible = false;
    for (const auto h : hands_) scene.edit(h).visible = false;
  }

 private:
  static void set(renderer::Scene& scene, std::size_t i, bool visible, const geometry::Isometry& pose) {
    const auto& o = scene.objects()[i];
    if (o.visible == visible && o.pose.m == pose.m) return;
    auto& e = scene.edit(i);
    e.visible = visible;
    e.pose = pose;
  }
  struct Sample {
    std::int64_t t_ns;
    glm::dvec3 local_m;
  };
  geometry::Space space_;
  glm::dvec3 tip_offset_m_;
  std::size_t cue_ = 0;
  std::array<std::size_t, 2> hands_{};
  std::vector<Sample> history_;
  mutable phys::Vec2 aim_{0.0, -1.0};
};

// The partner in a shared game (docs/shared_play.md, "The partner seen"):
// a head with a face card (the partner's photo or initials) in front of it,
// two hands and a cue placed each frame from the partner's stream at this
// frame's display time (PartnerPoseBuffer), hidden where the partner's
// tracking or the stream is lost. The objects are ordinary scene objects, so
// every view mode draws them, and in S3 their antipodal images too.
class PartnerAvatar {
 public:
  PartnerAvatar(renderer::Scene& scene, const geometry::Space& space, renderer::CoverageBitmap face)
      : space_(space),
        // The card just in front of the head, turned to face where it looks
        // (the panel's front is its +z; the head looks along −z).
        face_offset_(geometry::translation_m(space, {0.0, 0.0, -0.115}) *
                     geometry::rotation(glm::dvec3(0.0, 1.0, 0.0), kPi)) {
    head_ = scene.add(renderer::ball_object(space, 0.11, renderer::display(0.25f, 0.45f, 0.85f), {}));
    face_ = scene.add(renderer::image_panel_object(space, "partner_face", std::move(face), kFaceWidth_m,
                                                   kFaceHeight_m, {}));
    for (auto& h : hands_) h = scene.add(renderer::ball_object(space, 0.04, renderer::display(0.35f, 0.55f, 0.9f), {}));
    geometry::BentStick stick;
    stick.length_m = TrackedCue::kLength_m;
    stick.radius_m = 0.0065;
    cue_ = scene.add(renderer::stick_object(space, stick, {}));
    hide(scene);
  }

  void update(renderer::Scene& scene, const net::PartnerPose& p) {
    auto set = [&](std::size_t i, int device, const geometry::Isometry& pose) {
      const bool visible = p.valid && (p.tracked & (1u << device)) != 0;
      const auto& o = scene.objects()[i];
      if (o.visible == visible && (!visible || o.pose.m == pose.m)) return;  // an unchanged frame stays unchanged
      auto& e = scene.edit(i);
      e.visible = visible;
      if (visible) e.pose = pose;
    };
    set(head_, net::PoseFrame::head, p.pose[net::PoseFrame::head]);
    set(face_, net::PoseFrame::head, p.pose[net::PoseFrame::head] * face_offset_);
    set(hands_[0], net::PoseFrame::left_hand, p.pose[net::PoseFrame::left_hand]);
    set(hands_[1], net::PoseFrame::right_hand, p.pose[net::PoseFrame::right_hand]);
    // The stick's model chord along x, centred: turned along the tip's −z,
    // its front end at the tip (as this station's own cue).
    set(cue_, net::PoseFrame::cue,
        p.pose[net::PoseFrame::cue] * geometry::rotation(glm::dvec3(0.0, 1.0, 0.0), kPi / 2.0) *
            geometry::translation_m(space_, {-TrackedCue::kLength_m / 2.0, 0.0, 0.0}));
  }

  void hide(renderer::Scene& scene) const {
    for (std::size_t i : {head_, face_, hands_[0], hands_[1], cue_})
      if (scene.objects()[i].visible) scene.edit(i).visible = false;
  }

  // A new face (the partner's photo arrived, or it came back with another).
  void set_face(renderer::Scene& scene, renderer::CoverageBitmap face) {
    const auto& o = scene.objects()[face_];
    scene.replace_mesh(face_, o.build, o.info, std::move(face));
  }

 private:
  static constexpr double kFaceWidth_m = 0.16, kFaceHeight_m = 0.2;
  geometry::Space space_;
  geometry::Isometry face_offset_;  // head → face card
  std::size_t head_ = 0, face_ = 0, cue_ = 0;
  std::array<std::size_t, 2> hands_{};
};

class PlayBlock {
 public:
  explicit PlayBlock(BlockRun& run)
      : run_(run),
        f_(run.frames),
        play_(f_.protocol.blocks[run.block.protocol_block].play),
        params_(play_parameters(play_)) {}

  Outcome run() {
    begin();
    const std::int64_t start_ns = f_.clock.now_ns();
    next_shot_ns_ = start_ns + think_ns();
    // The simulated player walks round the physical table while it plays.
    struct Restore {
      SessionFrames& f;
      ~Restore() { f.lab_override = nullptr; }
    } restore{f_};
    const geometry::PhysicalTable physical = f_.physical_table();
    if (simulated_) walk_around(physical, start_ns);
    const std::string line = run_.block.name + "  play: strike the white ball with the cue";
    const std::string paused =
        run_.block.name + "  paused: the partner station is disconnected; the game goes on when it is back";
    io::Overlay overlay{Phase::stimulus, line, !simulated_};
    std::optional<Rolling> rolling;
    for (;;) {
      Frame g;
      if (!f_.begin(g)) return Outcome::quit;
      if (g.signal == Signal::pause) {
        if (f_.hold(Phase::stimulus, trial_id_) == Outcome::quit) return Outcome::quit;
        continue;
      }
      const std::int64_t t_ns = g.timing.predicted_display_ns;
      figures_.add(f_.lab(), physical, f_.tracking());
      if (shared_) {
        exchange(t_ns);
        const net::PartnerPose partner = partner_poses_.at(t_ns);
        avatar_->update(f_.scene().scene(), partner);
        log_partner(g, partner);
        show_link(t_ns);
        const std::string& now = partner_away_ ? paused : line;
        if (overlay.text != now) overlay.text = now;  // no copy on an unchanged frame
      }
      if (!rolling) {
        if (const auto why = between_shots(g, t_ns, start_ns, rolling)) {
          ended_ = *why;
          f_.end(g, overlay, false, trial_id_);
          break;
        }
      }
      if (rolling && roll(*rolling, t_ns)) {
        commit_shot(*rolling, t_ns, static_cast<double>(g.timing.now_ns - start_ns) * 1e-9);
        rolling.reset();
        next_shot_ns_ = g.timing.now_ns + think_ns();
      }
      f_.end(g, overlay, false, trial_id_);
      if (g.signal == Signal::quit) return Outcome::quit;
    }
    f_.room.status.partner.clear();
    store_play(start_ns);
    scene_->hide(f_.scene().scene());
    if (cue_) cue_->hide(f_.scene().scene());
    if (avatar_) avatar_->hide(f_.scene().scene());
    return Outcome::done;
  }

 private:
  struct Rolling {
    std::int64_t strike_ns = 0;
    bl::ShotSpec spec;
    bl::ShotOutcome outcome;
    phys::System system;
    std::optional<std::string> cue_pose;
    phys::Strike strike;
    std::optional<net::Shot> from_partner;  // shared: the partner's shot as it sent it
    std::size_t events_shown = 0;           // of outcome.events, replayed by `system`
  };

  // The block's one trial begun: its world, the balls where the last stored
  // shot left them, the cue, and in a shared game the partner.
  void begin() {
    index_ = run_.block.first_trial;
    trial_id_ = f_.trial_ids[index_];
    const auto& planned = f_.design.trials[index_];
    f_.prepare(planned.settings, "");
    f_.set_current_trial(index_);
    f_.writer.journal(data::BeginTrial{trial_id_});
    const World& world = f_.world();
    cloth_ = phys::make_cloth(world.space, world.table);
    load_rest_state();
    add_objects();
    rest_.emplace(bl::at_rest(cloth_, params_, balls_));
    simulated_ = f_.options().observer.has_value();
    shared_ = f_.options().shared;
    if (shared_) {
      partner_completed_ = shared_->partner_completed_shots;
      avatar_.emplace(f_.scene().scene(), f_.world().space, face());
      start_shared();
    }
    const auto& tip = f_.protocol.calibration.tip_offset_m;
    tip_offset_m_ = {tip[0], tip[1], tip[2]};
    if (!simulated_) cue_.emplace(f_.scene().scene(), f_.world().space, tip_offset_m_);
    rng_.seed(protocol::mix_seed(f_.design.seed ^ protocol::mix_seed(0x9a1e0000ULL + index_)));
    duration_ns_ = play_.duration_s * 1e9 - elapsed_before_s_ * 1e9;
  }

  // The simulated player's walk round the physical table, as the lab pose of
  // each frame.
  void walk_around(const geometry::PhysicalTable& physical, std::int64_t start_ns) {
    walk_ = walking_trajectory(physical);
    if (walk_.empty()) return;
    f_.lab_override = [this, start_ns](const io::FrameTiming& t) {
      const std::int64_t period = walk_[1].t_ns - walk_[0].t_ns;
      const auto k = static_cast<std::size_t>(std::max<std::int64_t>(0, t.predicted_display_ns - start_ns) / period);
      return walk_[std::min(k, walk_.size() - 1)].frame;
    };
  }

  // While no ball rolls: the partner's next shot, this station's strike, or
  // the end of the game (why it ended).
  std::optional<std::string> between_shots(const Frame& g, std::int64_t t_ns, std::int64_t start_ns,
                                           std::optional<Rolling>& rolling) {
    const bool out_of_time = static_cast<double>(g.timing.now_ns - start_ns) > duration_ns_;
    const auto next = shared_ ? pending_.find(static_cast<std::uint32_t>(shots_)) : pending_.end();
    if (next != pending_.end()) {
      // The partner's shot — or, for a station that came back behind, one it
      // missed, sent again.
      rolling = start_partner_shot(next->second, t_ns);
      pending_.erase(pending_.begin(), std::next(next));
      return std::nullopt;
    }
    if (shared_ && partner_lost(t_ns)) return "partner_lost";
    if (shared_ && (!my_turn() || partner_completed_ > shots_)) {
      // The partner's turn, or shots this station missed still to come: wait
      // for them, or for the end the partner decided.
      if (partner_completed_ <= shots_) {
        if (auto why = end_reason(false)) return why;
        if (partner_over_) return "partner_ended";
      }
      std::optional<std::string> ignored;
      (void)take_strike(g, t_ns, ignored);  // draws the cue; not this station's turn
      return std::nullopt;
    }
    if (auto why = end_reason(out_of_time)) {
      if (shared_) send_game_over();
      return why;
    }
    std::optional<std::string> cue_pose;
    auto spec = take_strike(g, t_ns, cue_pose);
    if (shared_ && partner_away_) spec.reset();  // paused until the partner is back
    if (spec) {
      rolling = start_shot(t_ns, *spec, cue_pose);
      if (shared_) send_shot(*rolling);
    }
    return std::nullopt;
  }

  // The rolling balls advanced to this frame and shown; true once they rest
  // (or the shot's time is up).
  bool roll(Rolling& r, std::int64_t t_ns) {
    const double t_s = static_cast<double>(t_ns - r.strike_ns) * 1e-9;
    // The same events as the outcome's, and no more (one stopped at its
    // event limit ends there).
    while (r.events_shown < r.outcome.events.size() && r.system.next_event(t_s)) ++r.events_shown;
    show(r.system, t_s);
    return r.system.all_still() || t_s > r.outcome.end_s ||
           (r.outcome.event_limit && r.events_shown == r.outcome.events.size());
  }

  // ---- Shared play (docs/shared_play.md)

  [[nodiscard]] bool my_turn() const { return (shots_ % 2 == 0) == (shared_->mine.role == net::Role::host); }

  void start_shared() {
    events::SharedGame e;
    e.game_uuid = uuid_text(shared_->game_uuid);
    e.role = std::string(net::to_string(shared_->mine.role));
    e.partner_initials = shared_->partner.initials;
    e.partner_version = shared_->partner.software_version;
    e.completed_shots = shots_;
    f_.event(trial_id_, e);
    // Where this station's game stands: a station that comes back behind its
    // partner is sent the shots it missed.
    send_game_state(net::GameState::Phase::playing);
  }

  void send_game_state(net::GameState::Phase phase) {
    net::GameState g;
    g.game_uuid = shared_->game_uuid;
    g.phase = phase;
    g.completed_shots = static_cast<std::uint32_t>(shots_);
    g.next_shooter = shots_ % 2 == 0 ? net::Role::host : net::Role::join;
    g.balls = static_cast<std::uint16_t>(balls_.size());
    shared_->send(g);
    shared_->flush();
  }

  // The partner disconnected: the game pauses (no new shot) until it is back.
  void partner_left(std::int64_t t_ns) {
    if (partner_away_) return;
    partner_away_ = true;
    away_since_ns_ = t_ns;
    f_.event(trial_id_, events::PartnerLeft{shots_}, t_ns);
  }

  // A partner away for longer than the station waits for one (--partner-wait-s)
  // ends the game here: the stored shots stay, and a resumed run goes on.
  [[nodiscard]] bool partner_lost(std::int64_t t_ns) const {
    return partner_away_ && t_ns - away_since_ns_ > shared_->options.wait_ns;
  }

  // A partner connected (again): both sides say who they are and where their
  // game stands.
  void partner_connected() {
    // The hello names this station's game and where it stands, so that a
    // host that was killed and resumed rejoins the game.
    shared_->mine.game_uuid = shared_->game_uuid;
    shared_->mine.completed_shots = static_cast<std::uint32_t>(shots_);
    shared_->send(shared_->mine);
    if (shared_->options.avatar) shared_->send(*shared_->options.avatar);
    send_game_state(net::GameState::Phase::playing);
  }

  // The partner's face: its photo, or its initials.
  renderer::CoverageBitmap face() {
    return f_.check(avatar_face(shared_->partner_avatar, shared_->partner.initials, f_.font()));
  }

  void partner_hello(const net::Hello& h, std::int64_t t_ns) {
    if (const auto why = net::incompatibility(shared_->mine, h)) {
      shared_->send(net::Bye{net::Bye::Reason::incompatible, *why});
      shared_->flush();
      return;
    }
    shared_->partner = h;
    if (!partner_away_) return;
    partner_away_ = false;
    f_.event(trial_id_, events::PartnerBack{shots_, static_cast<double>(t_ns - away_since_ns_) * 1e-9}, t_ns);
  }

  // Each frame: what the partner sent, this station's poses out, and the
  // clock estimate stored every 5 s.
  void exchange(std::int64_t t_ns) {
    SharedPlay& link = *shared_;
    const net::Poll poll = link.take();
    if (poll.disconnected) partner_left(t_ns);
    if (poll.connected) partner_connected();
    if (!link.connected() && shared_->mine.role == net::Role::join && t_ns >= next_reconnect_ns_) {
      link.reconnect();
      next_reconnect_ns_ = t_ns + 1'000'000'000;
    }
    for (const auto& r : poll.messages) {
      if (const auto* shot = std::get_if<net::Shot>(&r.message)) {
        // Kept by index: a partner whose last shot came to rest sooner on its
        // table may strike the next one before this station has stored it.
        if (static_cast<int>(shot->shot_index) >= shots_ && shot->cue_ball < static_cast<int>(balls_.size()))
          pending_.emplace(shot->shot_index, *shot);
      } else if (const auto* g = std::get_if<net::GameState>(&r.message)) {
        if (g->phase == net::GameState::Phase::over) partner_over_ = true;
        partner_completed_ = std::max<std::int64_t>(partner_completed_, g->completed_shots);
        // Behind: the shots it missed, as they were played.
        for (auto it = history_.lower_bound(g->completed_shots); it != history_.end(); ++it) link.send(it->second);
      } else if (const auto* h = std::get_if<net::Hello>(&r.message)) {
        partner_hello(*h, t_ns);
      } else if (const auto* bye = std::get_if<net::Bye>(&r.message)) {
        // The game over; a partner that quit (interrupted) is a pause.
        if (bye->reason == net::Bye::Reason::done) partner_over_ = true;
        if (bye->reason == net::Bye::Reason::quitting) partner_left(t_ns);
      } else if (const auto* photo = std::get_if<net::Avatar>(&r.message)) {
        shared_->partner_avatar = *photo;
        avatar_->set_face(f_.scene().scene(), face());
      } else if (const auto* pose = std::get_if<net::PoseFrame>(&r.message)) {
        partner_poses_.push(*pose, link.to_local_ns(pose->display_ns));
      }
    }
    send_poses(t_ns);
    const net::ClockEstimate c = link.clock();
    if (c.valid && t_ns >= next_clock_event_ns_) {
      f_.event(trial_id_, events::PartnerClock{c.offset_ns, c.round_trip_ns, c.uncertainty_ns,
                                               static_cast<std::int64_t>(c.samples)});
      next_clock_event_ns_ = t_ns + 5'000'000'000;
    }
    link.flush();
  }

  // The operator's line about the shared game, twice a second: both
  // players, the link's state and figures, and how far apart the heads are.
  void show_link(std::int64_t t_ns) {
    if (t_ns < next_link_line_ns_) return;
    next_link_line_ns_ = t_ns + 500'000'000;
    const net::LinkCounters c = shared_->counters();
    const net::ClockEstimate clock = shared_->clock();
    char figures[160];
    std::snprintf(figures, sizeof figures, "  RTT %u ms  loss %.0f %%", c.enet_rtt_ms, 100.0 * c.enet_loss);
    std::string line = "you " + std::string(to_string(shared_->mine.role)) + " " + shared_->mine.initials +
                       ", partner " + std::string(to_string(shared_->partner.role)) + " " +
                       shared_->partner.initials + ": " +
                       (partner_away_ ? "DISCONNECTED, game paused" : "connected") + figures;
    if (clock.valid) {
      std::snprintf(figures, sizeof figures, "  clock offset %+.2f ms", static_cast<double>(clock.offset_ns) / 1e6);
      line += figures;
    }
    if (last_distance_m_ >= 0.0) {
      std::snprintf(figures, sizeof figures, "  heads %.2f m apart", last_distance_m_);
      line += figures;
    }
    f_.room.status.partner = std::move(line);
  }

  // The partner as this frame draws it (partner_samples), with the two
  // heads' geodesic distance in the virtual space where this head is known.
  void log_partner(const Frame& g, const net::PartnerPose& partner) {
    if (!partner.valid) return;
    static constexpr data::TrackedDevice devices[net::PoseFrame::kDevices] = {
        data::TrackedDevice::head, data::TrackedDevice::left_hand, data::TrackedDevice::right_hand,
        data::TrackedDevice::other};
    const geometry::TrackingOutput* mine = f_.tracking();
    const geometry::Space& space = f_.world().space;
    for (int d = 0; d < net::PoseFrame::kDevices; ++d) {
      data::TrackingSample s;
      s.partner = true;
      s.device = devices[d];
      s.position_valid = (partner.tracked & (1u << d)) != 0;
      s.extrapolated = partner.extrapolated;
      s.sample_age_ns = g.timing.predicted_display_ns - partner.newest_sample_ns;
      store_pose(partner.pose[static_cast<std::size_t>(d)].m, s.virtual_pose);
      if (d == net::PoseFrame::head && mine != nullptr && mine->tracked[0]) {
        s.distance_m = geometry::distance_m(space, mine->pose[0] * geometry::origin(space),
                                            partner.pose[0] * geometry::origin(space));
        last_distance_m_ = s.distance_m;
      }
      f_.log_sample(g, trial_id_, s);
    }
  }

  // Head, hands and cue tip as this station's tracking placed them.
  void send_poses(std::int64_t t_ns) {
    const geometry::TrackingOutput* t = f_.tracking();
    if (t == nullptr) return;
    net::PoseFrame m;
    m.sequence = ++pose_sequence_;
    m.display_ns = t_ns;
    m.space = f_.world().space.kind;
    m.radius_m = f_.world().space.radius_m;
    for (int d = 0; d < 3; ++d) {
      m.pose[static_cast<std::size_t>(d)] = t->pose[static_cast<std::size_t>(d)];
      if (t->tracked[static_cast<std::size_t>(d)]) m.tracked |= static_cast<std::uint8_t>(1u << d);
    }
    m.pose[net::PoseFrame::cue] = t->pose[2] * geometry::translation_m(f_.world().space, tip_offset_m_);
    if (t->tracked[2]) m.tracked |= 1u << net::PoseFrame::cue;
    shared_->send(m);
  }

  void send_shot(const Rolling& r) {
    net::Shot m;
    m.shot_index = static_cast<std::uint32_t>(shots_);
    m.shooter = shared_->mine.role;
    m.simulated = simulated_;
    m.strike_ns = r.strike_ns;
    m.cue_ball = 0;
    m.toward_x_m = r.spec.toward_m.x;
    m.toward_z_m = r.spec.toward_m.y;
    m.cue_speed_m_s = r.spec.cue_speed_m_s.value_or(0.0);
    m.tip_side = r.spec.tip.x;
    m.tip_height = r.spec.tip.y;
    for (const auto& e : r.outcome.events) {
      if (m.events.size() == net::kMaxEvents) break;
      m.events.push_back({e.event.t_s, static_cast<std::uint8_t>(e.event.kind), static_cast<std::int16_t>(e.event.a),
                          static_cast<std::int16_t>(e.event.b), static_cast<std::int16_t>(e.event.cushion),
                          static_cast<std::int16_t>(e.event.pocket)});
    }
    for (const auto& b : bl::rest_state(r.outcome))
      m.rest.push_back({b.native_m.x, b.native_m.y, b.pocketed, static_cast<std::int8_t>(b.pocket)});
    history_[m.shot_index] = m;
    shared_->send(m);
    shared_->flush();
  }

  void send_game_over() { send_game_state(net::GameState::Phase::over); }

  // The partner's shot from its inputs, struck when the partner struck it
  // (on this station's clock), so both tables show the balls rolling together.
  Rolling start_partner_shot(const net::Shot& m, std::int64_t t_ns) {
    bl::ShotSpec spec;
    spec.ball = balls_[static_cast<std::size_t>(m.cue_ball)].id;
    spec.toward_m = {m.toward_x_m, m.toward_z_m};
    spec.cue_speed_m_s = m.cue_speed_m_s;
    spec.tip = {m.tip_side, m.tip_height};
    const std::int64_t strike_ns = std::min(t_ns, shared_->to_local_ns(m.strike_ns));
    Rolling r = start_shot(strike_ns, spec, std::nullopt);
    r.from_partner = m;
    return r;
  }

  // The partner's shot as simulated here against what it sent: the same
  // events, and the largest distance between rest places.
  static std::pair<bool, double> compare(const Rolling& r, const std::vector<bl::BallPlace>& mine) {
    const net::Shot& m = *r.from_partner;
    bool same = m.events.size() == r.outcome.events.size();
    for (std::size_t i = 0; same && i < m.events.size(); ++i) {
      const auto& a = m.events[i];
      const auto& b = r.outcome.events[i].event;
      same = a.t_s == b.t_s && a.kind == static_cast<std::uint8_t>(b.kind) && a.a == b.a && a.b == b.b &&
             a.cushion == b.cushion && a.pocket == b.pocket;
    }
    double diff = 0.0;
    if (m.rest.size() != mine.size()) return {false, 0.0};
    for (std::size_t i = 0; i < mine.size(); ++i) {
      diff = std::max(diff, std::hypot(m.rest[i].x_m - mine[i].native_m.x, m.rest[i].z_m - mine[i].native_m.y));
      if (m.rest[i].pocketed != mine[i].pocketed || m.rest[i].pocket != mine[i].pocket) same = false;
    }
    return {same, diff};
  }

  void store_network() {
    const net::LinkCounters c = shared_->counters();
    events::SharedNetwork e;
    e.rtt_ms = c.enet_rtt_ms;
    e.loss = c.enet_loss;
    e.poses_received = static_cast<std::int64_t>(c.poses_received);
    e.poses_late = static_cast<std::int64_t>(c.poses_late);
    e.poses_lost = static_cast<std::int64_t>(c.poses_lost);
    e.bytes_sent = static_cast<std::int64_t>(c.wire_bytes_sent);
    e.bytes_received = static_cast<std::int64_t>(c.wire_bytes_received);
    e.dropped = static_cast<std::int64_t>(c.dropped.total());
    e.disconnects = static_cast<std::int64_t>(c.disconnects);
    f_.event(trial_id_, e);
  }

  // Laps enough for the whole block at a slow walk, 0.4 m/s. In a shared
  // game the joiner starts across the table from the host, as two players
  // do, so the two simulated players never stand in one place.
  geometry::Trajectory walking_trajectory(const geometry::PhysicalTable& table) const {
    geometry::WalkAroundOptions o;
    o.common.table = table;
    o.speed_m_s = 0.4;
    if (shared_ != nullptr && shared_->mine.role == net::Role::join) o.start_azimuth_rad = kPi;
    const double circle_m = 2.0 * kPi * (0.5 * table.edge_m + o.common.head_distance_m);
    o.laps = std::ceil(play_.duration_s * o.speed_m_s / circle_m) + 1.0;
    return geometry::walk_around(o);
  }

  // This frame's strike, if any: the simulated player's when its thinking
  // time is up; the tracked cue's tip entering the cue ball; the desktop's
  // strike key held and let go.
  std::optional<bl::ShotSpec> take_strike(const Frame& g, std::int64_t t_ns, std::optional<std::string>& cue_pose) {
    std::optional<bl::ShotSpec> spec;
    if (simulated_ && g.timing.now_ns >= next_shot_ns_) spec = choose_shot(*rest_, balls_, params_, rng_);
    if (cue_ && f_.tracking() != nullptr) {
      cue_->update(f_.scene().scene(), *f_.tracking(), cue_ball_pose(), t_ns);
      if (auto s = cue_->strike(params_.radius_m)) {
        s->ball = balls_[0].id;
        s->toward_m = toward_along(*rest_, cue_->aim());
        spec = s;
        cue_pose = lab_cue_pose();
      }
    }
    // The desktop's cue: hold the key, let go to strike.
    for (const auto& in : g.inputs) {
      if (!in.intents.has(io::Intent::cue_strike)) continue;
      if (in.pressed) {
        charge_from_ns_ = in.t_ns;
      } else if (charge_from_ns_) {
        const double held_s = static_cast<double>(in.t_ns - *charge_from_ns_) * 1e-9;
        charge_from_ns_.reset();
        if (held_s < 0.15) continue;  // a tap (a page's key) is not a stroke
        spec = sighted_shot(*rest_, balls_, f_.head());
        spec->cue_speed_m_s = std::clamp(0.8 + 3.0 * held_s, 0.8, 7.0);
      }
    }
    return spec;
  }

  // The block's figures (a play_summary event and the run summary) and its
  // one trial, completed.
  void store_play(std::int64_t start_ns) {
    if (shared_) store_network();
    events::PlaySummary summary;
    summary.block = run_.block.name;
    summary.ended = ended_;
    summary.shots = shots_;
    summary.pocketed = pocketed_;
    summary.time_s = static_cast<double>(f_.clock.now_ns() - start_ns) * 1e-9 + elapsed_before_s_;
    summary.walked_m = figures_.walked_m;
    summary.laps_physical = figures_.physical.laps();
    summary.laps_virtual = figures_.virtual_table.laps();
    summary.hand_error_m =
        figures_.hand_error_n > 0 ? figures_.hand_error_sum_m / static_cast<double>(figures_.hand_error_n) : 0.0;
    f_.event(trial_id_, summary);
    f_.summary.play.push_back(summary);
    data::TrialResult r;
    r.trial_id = trial_id_;
    r.onset_ns = start_ns;
    r.response_ns = f_.clock.now_ns();
    r.response = std::to_string(shots_) + " shots, " + std::to_string(pocketed_) + " pocketed";
    r.response_device = simulated_ ? "simulated" : "participant";
    f_.check(f_.writer.wait_durable(f_.writer.journal(std::move(r))));
    f_.report_trial(index_, data::TrialStatus::completed, "");
  }

  std::int64_t think_ns() {
    return static_cast<std::int64_t>((1.5 + 1.5 * protocol::uniform01(rng_)) * 1e9);
  }

  // Why the game is over, if it is: its time is up, its shots are played,
  // every object ball is pocketed (until = "all_pocketed"), or there are no balls.
  std::optional<std::string> end_reason(bool out_of_time) const {
    if (out_of_time) return "time";
    if (play_.shots > 0 && shots_ >= play_.shots) return "shots";
    if (play_.until_all_pocketed) {
      bool any = false;
      for (std::size_t i = 1; i < balls_.size(); ++i) any = any || !balls_[i].pocketed;
      if (!any) return "all_pocketed";
    }
    if (balls_.empty()) return "no_balls";
    return std::nullopt;
  }

  // A pocketed cue ball comes back on its spot, halfway from the centre to
  // edge 0, or the nearest free place toward the centre and beyond.
  void respot_cue_ball() {
    const double apothem = cloth_.table.apothem_m();
    for (int k = 0; k <= 200; ++k) {
      const phys::Vec2 spot{0.0, apothem / 2.0 - static_cast<double>(k) * apothem / 200.0};
      const glm::dvec3 p = phys::from_native(cloth_, spot);
      bool free = true;
      for (std::size_t i = 1; i < balls_.size() && free; ++i)
        free = balls_[i].pocketed ||
               phys::distance_m(cloth_, p, phys::from_native(cloth_, balls_[i].native_m)) > 2.0 * params_.radius_m + 1e-6;
      if (free) {
        balls_[0] = {balls_[0].id, spot, false, -1};
        return;
      }
    }
  }

  void load_rest_state() {
    const auto stored = f_.check(f_.store.shots(trial_id_));
    if (!stored.empty()) {
      const Json rest = Json::parse(stored.back().rest_state);
      for (const auto& b : rest)
        balls_.push_back({b["id"].get<std::string>(), {b["x_m"].get<double>(), b["z_m"].get<double>()},
                          b.value("pocketed", false), b.value("pocket", -1)});
      shots_ = static_cast<int>(stored.size());
      for (const auto& s : stored) pocketed_ += static_cast<int>(Json::parse(s.pocketed).size());
      const Json settings = Json::parse(stored.back().table_settings);
      elapsed_before_s_ = settings.value("play_elapsed_s", 0.0);
      return;
    }
    auto rack = phys::rack(cloth_, params_, play_.rack);
    if (const auto* e = std::get_if<geometry::GeometryError>(&rack))
      throw Stop{{Error::Kind::bad_input, "block '" + run_.block.name + "': " + e->message}};
    for (const auto& b : std::get<std::vector<phys::RackBall>>(rack)) balls_.push_back({b.id, b.native_m, false, -1});
  }

  void add_objects() {
    f_.scene().show(Phase::iti, false);  // the trial stimuli stay hidden
    scene_.emplace(f_.scene().scene(), f_.world(), params_, balls_.size());
    show(bl::at_rest(cloth_, params_, balls_), 0.0);
  }

  void show(const phys::System& sys, double t_s) { scene_->show(f_.scene().scene(), sys, t_s); }

  // The cue ball's centre frame at rest (its frame lifted by R).
  geometry::Isometry cue_ball_pose() const {
    return phys::to_isometry(rest_->ball(0).frame) *
           geometry::translation_m(f_.world().space, {0.0, params_.radius_m, 0.0});
  }

  // The right hand and cue tip in the lab at the strike, for the shot's record.
  std::string lab_cue_pose() const {
    const auto& hand = f_.lab()[geometry::Device::right_hand];
    const glm::dvec3 tip = hand.position_m + hand.orientation * tip_offset_m_;
    return Json{{"tip_m", {tip.x, tip.y, tip.z}},
                {"hand_m", {hand.position_m.x, hand.position_m.y, hand.position_m.z}},
                {"orientation_xyzw", {hand.orientation.x, hand.orientation.y, hand.orientation.z, hand.orientation.w}}}
        .dump();
  }

  Rolling start_shot(std::int64_t t_ns, const bl::ShotSpec& spec, std::optional<std::string> cue_pose) {
    Rolling r{t_ns, spec, bl::simulate(cloth_, params_, balls_, spec, 120.0), *rest_, std::move(cue_pose),
              bl::strike_for(*rest_, params_, 0, spec), std::nullopt};
    if (!r.strike.miscue) r.system.set_motion(0, r.strike.v, r.strike.w);
    f_.event(trial_id_, events::Strike{shots_, spec.ball, glm::length(r.strike.v), r.strike.miscue}, t_ns);
    return r;
  }

  void commit_shot(const Rolling& r, std::int64_t rest_ns, double elapsed_s) {
    data::ShotRecord s;
    s.session_id = f_.session_id;
    s.trial_id = trial_id_;
    s.shot_index = shots_;
    s.t_ns = r.strike_ns;
    s.rest_ns = rest_ns;
    const bool simulated = r.from_partner ? r.from_partner->simulated : simulated_;
    s.player = simulated ? "simulated" : "participant";
    s.ball = r.spec.ball;
    // rest_ still holds the balls as they were struck.
    const phys::Vec2 aim =
        phys::direction_toward(cloth_, rest_->ball(0).frame, phys::from_native(cloth_, r.spec.toward_m));
    s.aim_x = aim.x;
    s.aim_z = aim.y;
    s.speed_m_s = glm::length(r.strike.v);
    s.cue_speed_m_s = r.spec.cue_speed_m_s;
    if (r.spec.cue_speed_m_s) {
      s.tip_side = r.spec.tip.x;
      s.tip_height = r.spec.tip.y;
    }
    s.miscue = r.outcome.miscue;
    s.cue_pose = r.cue_pose;
    const World& w = f_.world();
    Json settings{{"space", std::string(geometry::to_string(w.space.kind))},
                  {"edge_m", w.table.edge_m},
                  {"sides", w.table.sides},
                  {"parameters", bl::to_json(params_)},
                  {"play_elapsed_s", elapsed_before_s_ + elapsed_s}};
    s.table_settings = settings.dump();
    s.before_state = Json{{"balls", bl::to_json(balls_)}}.dump();
    s.shot = bl::to_json(r.spec).dump();
    const Json outcome = bl::to_json(r.outcome, balls_);
    s.events = outcome["events"].dump();
    s.event_count = static_cast<std::int64_t>(r.outcome.events.size());
    Json pocketed = Json::array();
    // Object balls only: a pocketed cue ball is a scratch, respotted below.
    for (std::size_t i = 1; i < balls_.size(); ++i)
      if (!balls_[i].pocketed && r.outcome.final[i].pocketed) pocketed.push_back(balls_[i].id);
    s.pocketed = pocketed.dump();
    for (const auto& e : r.outcome.events)
      if (e.event.kind == phys::EventKind::pocket)
        f_.event(trial_id_, events::Pocket{shots_, balls_[static_cast<std::size_t>(e.event.a)].id, e.event.pocket},
                 r.strike_ns + static_cast<std::int64_t>(e.event.t_s * 1e9));
    balls_ = bl::rest_state(r.outcome);
    std::optional<events::SharedShot> shared_shot;
    if (shared_) {
      shared_shot.emplace();
      shared_shot->shot_index = shots_;
      shared_shot->local = !r.from_partner;
      shared_shot->shooter = std::string(net::to_string(r.from_partner ? r.from_partner->shooter : shared_->mine.role));
    }
    if (r.from_partner) {
      history_[r.from_partner->shot_index] = *r.from_partner;
      // The shooter's station is the authority: its rest state is kept.
      const auto [same, diff] = compare(r, balls_);
      shared_shot->same_events = same;
      shared_shot->rest_difference_m = diff;
      if (r.from_partner->rest.size() == balls_.size())
        for (std::size_t i = 0; i < balls_.size(); ++i) {
          const auto& b = r.from_partner->rest[i];
          balls_[i] = {balls_[i].id, {b.x_m, b.z_m}, b.pocketed, b.pocket};
        }
    }
    if (balls_[0].pocketed) respot_cue_ball();
    s.rest_state = bl::to_json(balls_).dump();
    pocketed_ += static_cast<int>(pocketed.size());
    ++shots_;
    f_.check(f_.writer.wait_durable(f_.writer.journal(std::move(s))));
    if (shared_shot) f_.event(trial_id_, *shared_shot);
    f_.summary.shots += 1;
    f_.summary.balls_pocketed += static_cast<std::int64_t>(pocketed.size());
    rest_.emplace(bl::at_rest(cloth_, params_, balls_));
    show(*rest_, 0.0);
  }

  BlockRun& run_;
  SessionFrames& f_;
  const protocol::PlaySettings& play_;
  phys::Parameters params_;
  phys::Cloth cloth_;
  std::vector<bl::BallPlace> balls_;
  std::optional<PlayScene> scene_;
  std::size_t index_ = 0;
  std::int64_t trial_id_ = 0;
  int shots_ = 0;
  int pocketed_ = 0;
  double elapsed_before_s_ = 0.0;
  bool simulated_ = false;
  protocol::Engine rng_;
  geometry::Trajectory walk_;
  PlayFigures figures_;
  std::optional<phys::System> rest_;  // the balls at rest between shots
  std::optional<TrackedCue> cue_;
  glm::dvec3 tip_offset_m_{0.0};
  std::optional<std::int64_t> charge_from_ns_;
  SharedPlay* shared_ = nullptr;
  net::PartnerPoseBuffer partner_poses_;
  std::int64_t next_link_line_ns_ = 0;  // the operator's next line about the link
  double last_distance_m_ = -1.0;       // the heads' last distance; negative: not yet known
  std::optional<PartnerAvatar> avatar_;
  std::map<std::uint32_t, net::Shot> pending_;  // the partner's shots not yet played here, by index
  bool partner_over_ = false;
  bool partner_away_ = false;
  std::int64_t partner_completed_ = 0;  // the partner's completed shots, as it last said
  std::int64_t away_since_ns_ = 0;
  std::int64_t next_reconnect_ns_ = 0;
  std::map<std::uint32_t, net::Shot> history_;  // shared: the shots this station played or received, by index
  std::int64_t next_clock_event_ns_ = 0;
  std::int64_t next_shot_ns_ = 0;  // when the simulated player strikes next
  double duration_ns_ = 0.0;       // the block's time left when it began
  std::string ended_;              // why the game ended (play_summary's "ended")
  std::uint32_t pose_sequence_ = 0;
};

class PlayKind final : public BlockKind {
 public:
  [[nodiscard]] std::string_view name() const override { return "play"; }
  [[nodiscard]] std::size_t resume_position(const protocol::PlannedBlock&, std::size_t) const override { return 0; }
  Outcome run(BlockRun& run) const override { return PlayBlock(run).run(); }
};

}  // namespace

const BlockKind& play_block_kind() {
  static const PlayKind kind;
  return kind;
}

}  // namespace curvlab::harness::runner
