// Representative messages of every type, for the codec and link tests.
#pragma once

#include <cmath>
#include <vector>

#include <curvlab/geometry/isometry.hpp>
#include <curvlab/harness/net/handshake.hpp>
#include <curvlab/harness/net/messages.hpp>

namespace curvlab::test {

inline harness::net::PoseFrame pose_frame(geometry::SpaceKind kind, std::uint32_t sequence) {
  using namespace curvlab::geometry;
  const Space space{kind, kind == SpaceKind::E3 ? 1.0 : 0.8};
  harness::net::PoseFrame p;
  p.sequence = sequence;
  p.display_ns = 1'000'000'000LL + 11'111'111LL * sequence;
  p.space = kind;
  p.radius_m = space.radius_m;
  p.tracked = 0b1101;  // the left hand (bit 1) lost
  const double s = 0.01 * sequence;
  p.pose[0] = translation_m(space, {0.1 + s, 1.6, 0.4}) * rotation(Vec3{0.0, 1.0, 0.0}, 0.3 + s);
  p.pose[1] = Isometry{Mat4(0.0)};  // not tracked: anything finite
  p.pose[2] = translation_m(space, {0.3, 1.0 - s, 0.2}) * rotation(Vec3{1.0, 0.0, 0.0}, -0.7);
  p.pose[3] = translation_m(space, {0.25, 0.9, -0.3 + s}) * rotation(glm::normalize(Vec3{1.0, 2.0, 3.0}), 1.1);
  return p;
}

inline harness::net::Shot shot(std::uint32_t index) {
  harness::net::Shot s;
  s.shot_index = index;
  s.shooter = index % 2 ? harness::net::Role::join : harness::net::Role::host;
  s.strike_ns = 5'000'000'000LL + index;
  s.cue_ball = 0;
  s.toward_x_m = 0.5 * std::sin(0.1 * index);
  s.toward_z_m = 0.5 * std::cos(0.1 * index);
  s.cue_speed_m_s = 1.5;
  s.tip_side = 0.1;
  s.tip_height = -0.2;
  for (int i = 0; i < 5; ++i)
    s.events.push_back({0.1 * i, static_cast<std::uint8_t>(i % 6), 0, static_cast<std::int16_t>(i % 2 ? 1 : -1),
                        static_cast<std::int16_t>(i == 2 ? 3 : -1), -1});
  for (int b = 0; b < 3; ++b) {
    harness::net::ShotBall ball;
    ball.x_m = 0.01 * b;
    ball.z_m = -0.2;
    ball.pocketed = b == 2;
    ball.pocket = b == 2 ? 1 : -1;
    s.rest.push_back(ball);
  }
  return s;
}

inline harness::net::Hello hello(harness::net::Role role) {
  harness::net::Parameters params = {{"space", "S3"}, {"table.edge_m", "1.27"}, {"rack", "triangle-3"}};
  return harness::net::make_hello(role, "0.1.0", std::string(64, 'a'), params, "AB");
}

inline std::vector<harness::net::Message> every_message() {
  using namespace curvlab::harness::net;
  GameState g;
  g.game_uuid = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16};
  g.phase = GameState::Phase::playing;
  g.completed_shots = 7;
  g.next_shooter = Role::join;
  g.rack_seed = 0x1234567890abcdefULL;
  g.balls = 3;
  return {hello(Role::host),
          pose_frame(geometry::SpaceKind::S3, 3),
          pose_frame(geometry::SpaceKind::E3, 4),
          pose_frame(geometry::SpaceKind::H3, 5),
          shot(2),
          g,
          Ping{9, -123456789},
          Pong{9, 1, 2, 3},
          Bye{Bye::Reason::quitting, "the experimenter ended the session"},
          Avatar{3, 2, {0, 64, 128, 192, 255, 7}}};
}

}  // namespace curvlab::test
