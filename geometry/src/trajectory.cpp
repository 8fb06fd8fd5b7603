#include "curvlab/geometry/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace curvlab::geometry {
namespace {

constexpr double kPi = std::numbers::pi;

std::int64_t frame_time_ns(std::int64_t i, double rate_hz) {
  return std::llround(static_cast<double>(i) * 1e9 / rate_hz);
}

// Number of frame intervals needed to cover `seconds` at rate_hz (≥ 1).
std::int64_t intervals(double seconds, double rate_hz) {
  return std::max<std::int64_t>(1, std::llround(seconds * rate_hz));
}

// Facing azimuth φ of the table (seen from the device at azimuth φ, the table
// centre lies along −z after a yaw of φ), pitched down by pitch_down_rad.
Quat facing(double yaw_rad, double pitch_down_rad) {
  return glm::angleAxis(yaw_rad, Vec3(0.0, 1.0, 0.0)) *
         glm::angleAxis(-pitch_down_rad, Vec3(1.0, 0.0, 0.0));
}

LabPose pose_at(const Vec3& p, const Quat& q) { return {p, q, true}; }

Vec3 on_rail(const TrajectoryCommon& c, double u) {
  return c.table.rail_point_m(u) + Vec3(0.0, c.hand_height_m, 0.0);
}

double standing_radius_m(const TrajectoryCommon& c) {
  return 0.5 * c.table.edge_m + c.head_distance_m;
}

}  // namespace

Trajectory walk_around(const WalkAroundOptions& o) {
  const TrajectoryCommon& c = o.common;
  const double radius = standing_radius_m(c);
  const double laps = std::abs(o.laps);
  const int dir = o.direction < 0 ? -1 : +1;
  const std::int64_t n = intervals(2.0 * kPi * radius * laps / o.speed_m_s, c.rate_hz);
  const double spread_u = c.hand_spread_m / c.table.edge_m;
  Trajectory out;
  out.reserve(static_cast<std::size_t>(n + 1));
  for (std::int64_t i = 0; i <= n; ++i) {
    const double phi = o.start_azimuth_rad +
                       dir * 2.0 * kPi * laps * static_cast<double>(i) / static_cast<double>(n);
    TrajectorySample s;
    s.t_ns = frame_time_ns(i, c.rate_hz);
    const Vec3 head = c.table.polar_point_m(phi, radius, c.head_height_m);
    s.frame[Device::head] = pose_at(head, facing(c.table.yaw_rad + phi, kPi / 6.0));
    const double u = physical_anchor(c.table, head).perimeter_u(c.table.edge_m);
    const Quat hand_q = facing(c.table.yaw_rad + phi, 0.0);
    // Facing the centre, the left hand is clockwise of the head (lower u).
    s.frame[Device::left_hand] = pose_at(on_rail(c, u - spread_u), hand_q);
    s.frame[Device::right_hand] = pose_at(on_rail(c, u + spread_u), hand_q);
    out.push_back(s);
  }
  return out;
}

Trajectory head_square(const HeadSquareOptions& o) {
  const TrajectoryCommon& c = o.common;
  const double yaw = c.table.yaw_rad;
  const Vec3 start = c.table.polar_point_m(0.0, standing_radius_m(c), c.head_height_m);
  const Mat3 r = glm::mat3_cast(facing(yaw, 0.0));
  const double d = o.side_m;
  // Forward (−z), left (−x), back (+z), right (+x) in the head's own frame.
  const Vec3 corners[5] = {start, start + r * Vec3(0, 0, -d), start + r * Vec3(-d, 0, -d),
                           start + r * Vec3(-d, 0, 0), start};
  const std::int64_t per_leg = intervals(d / o.speed_m_s, c.rate_hz);
  const Quat q = facing(yaw, 0.0);
  const double u0 = 0.5;
  const double spread_u = c.hand_spread_m / c.table.edge_m;
  Trajectory out;
  out.reserve(static_cast<std::size_t>(4 * per_leg + 1));
  std::int64_t frame = 0;
  auto push = [&](const Vec3& head) {
    TrajectorySample s;
    s.t_ns = frame_time_ns(frame++, c.rate_hz);
    s.frame[Device::head] = pose_at(head, q);
    s.frame[Device::left_hand] = pose_at(on_rail(c, u0 - spread_u), q);
    s.frame[Device::right_hand] = pose_at(on_rail(c, u0 + spread_u), q);
    out.push_back(s);
  };
  push(corners[0]);
  for (int leg = 0; leg < 4; ++leg) {
    for (std::int64_t j = 1; j <= per_leg; ++j) {
      const double f = static_cast<double>(j) / static_cast<double>(per_leg);
      push(j == per_leg ? corners[leg + 1] : corners[leg] + f * (corners[leg + 1] - corners[leg]));
    }
  }
  return out;
}

Trajectory hand_lap(const HandLapOptions& o) {
  const TrajectoryCommon& c = o.common;
  const Vec3 head = c.table.polar_point_m(0.0, standing_radius_m(c), c.head_height_m);
  const Quat head_q = facing(c.table.yaw_rad, kPi / 6.0);
  const Quat hand_q = facing(c.table.yaw_rad, 0.0);
  const double u_head = physical_anchor(c.table, head).perimeter_u(c.table.edge_m);
  const double spread_u = c.hand_spread_m / c.table.edge_m;
  const std::int64_t n =
      intervals(4.0 * c.table.edge_m * std::abs(o.laps) / o.speed_m_s, c.rate_hz);
  Trajectory out;
  out.reserve(static_cast<std::size_t>(n + 1));
  for (std::int64_t i = 0; i <= n; ++i) {
    const double f = static_cast<double>(i) / static_cast<double>(n);
    TrajectorySample s;
    s.t_ns = frame_time_ns(i, c.rate_hz);
    s.frame[Device::head] = pose_at(head, head_q);
    s.frame[Device::left_hand] = pose_at(on_rail(c, u_head - spread_u), hand_q);
    s.frame[Device::right_hand] = pose_at(on_rail(c, u_head + spread_u + 4.0 * o.laps * f), hand_q);
    out.push_back(s);
  }
  return out;
}

Trajectory lean_over_centre(const LeanOverCentreOptions& o) {
  const TrajectoryCommon& c = o.common;
  const Vec3 from = c.table.polar_point_m(0.0, standing_radius_m(c), o.lean_height_m);
  const Vec3 to = c.table.polar_point_m(kPi, o.overshoot_m, o.lean_height_m);
  const Quat head_q = facing(c.table.yaw_rad, kPi / 3.0);
  const Quat hand_q = facing(c.table.yaw_rad, 0.0);
  const double spread_u = c.hand_spread_m / c.table.edge_m;
  const std::int64_t per_leg = intervals(glm::length(to - from) / o.speed_m_s, c.rate_hz);
  Trajectory out;
  out.reserve(static_cast<std::size_t>(2 * per_leg + 1));
  for (std::int64_t i = 0; i <= 2 * per_leg; ++i) {
    const std::int64_t j = i <= per_leg ? i : 2 * per_leg - i;
    const double f = static_cast<double>(j) / static_cast<double>(per_leg);
    TrajectorySample s;
    s.t_ns = frame_time_ns(i, c.rate_hz);
    s.frame[Device::head] = pose_at(from + f * (to - from), head_q);
    s.frame[Device::left_hand] = pose_at(on_rail(c, 0.5 - spread_u), hand_q);
    s.frame[Device::right_hand] = pose_at(on_rail(c, 0.5 + spread_u), hand_q);
    out.push_back(s);
  }
  return out;
}

void append_trajectory(Trajectory& head, const Trajectory& tail, double rate_hz) {
  if (tail.empty()) return;
  if (head.empty()) {
    head = tail;
    return;
  }
  const auto same = [](const LabFrame& a, const LabFrame& b) {
    for (std::size_t i = 0; i < kDeviceCount; ++i) {
      if (a.pose[i].position_m != b.pose[i].position_m ||
          a.pose[i].orientation != b.pose[i].orientation || a.pose[i].valid != b.pose[i].valid)
        return false;
    }
    return true;
  };
  const bool repeat = same(head.back().frame, tail.front().frame);
  const std::int64_t period = std::llround(1e9 / rate_hz);
  const std::int64_t shift =
      head.back().t_ns - tail.front().t_ns + (repeat ? 0 : period);
  for (std::size_t i = repeat ? 1 : 0; i < tail.size(); ++i) {
    TrajectorySample s = tail[i];
    s.t_ns += shift;
    head.push_back(s);
  }
}

}  // namespace curvlab::geometry
