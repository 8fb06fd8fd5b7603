// The partner's poses at this station's display time (partner_poses.hpp).
#include <gtest/gtest.h>

#include <curvlab/harness/net/partner_poses.hpp>

namespace net = curvlab::harness::net;
using namespace curvlab::geometry;

namespace {

constexpr std::int64_t kFrameNs = 11'111'111;  // 90 Hz

// A head walking at 1 m/s along x while turning at 1 rad/s, at time t.
Isometry walking(const Space& space, double t_s) {
  return translation_m(space, {t_s, 1.6, 0.0}) * rotation(Vec3{0.0, 1.0, 0.0}, t_s);
}

net::PoseFrame frame(const Space& space, std::uint32_t seq, std::int64_t t_ns) {
  net::PoseFrame f;
  f.sequence = seq;
  f.display_ns = t_ns;
  f.space = space.kind;
  f.radius_m = space.radius_m;
  f.tracked = 0b0001;
  f.pose[0] = walking(space, 1e-9 * static_cast<double>(t_ns));
  return f;
}

double max_diff(const Isometry& a, const Isometry& b) {
  double d = 0.0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) d = std::max(d, std::fabs(a.m[c][r] - b.m[c][r]));
  return d;
}

}  // namespace

TEST(NetPartnerPoses, InterpolatesAndExtrapolatesABoundedDistanceInEverySpace) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const Space space{kind, 0.9};
    net::PartnerPoseBuffer buf(50'000'000, 500'000'000);
    for (std::uint32_t i = 0; i < 10; ++i) buf.push(frame(space, i, kFrameNs * i), kFrameNs * i);
    // Half-way between two samples: within 3e-4 of the true pose (the head
    // sweeps a curve 1.6 m off the centre at 1 m/s and 1 rad/s; the blend's
    // error is second order in the 11 ms step, checked below).
    const std::int64_t mid = kFrameNs * 4 + kFrameNs / 2;
    const auto p = buf.at(mid);
    ASSERT_TRUE(p.valid);
    EXPECT_FALSE(p.extrapolated);
    EXPECT_LT(max_diff(p.pose[0], walking(space, 1e-9 * static_cast<double>(mid))), 3e-4) << to_string(kind);
    EXPECT_LT(isometry_error(space, p.pose[0]), 1e-12);
    // One frame past the newest: extrapolated, still close.
    const std::int64_t ahead = kFrameNs * 10;
    const auto q = buf.at(ahead);
    EXPECT_TRUE(q.extrapolated);
    EXPECT_EQ(q.newest_sequence, 9u);
    EXPECT_LT(max_diff(q.pose[0], walking(space, 1e-9 * static_cast<double>(ahead))), 3e-3) << to_string(kind);
    // Far past: held at the newest + 50 ms.
    const auto far = buf.at(kFrameNs * 9 + 300'000'000);
    const auto cap = buf.at(kFrameNs * 9 + 50'000'000);
    EXPECT_EQ(max_diff(far.pose[0], cap.pose[0]), 0.0);
    // Past the hold: the partner is lost.
    EXPECT_FALSE(buf.at(kFrameNs * 9 + 600'000'000).valid);
  }
}

TEST(NetPartnerPoses, TheBlendIsSecondOrderInTheStep) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const Space space{kind, 0.9};
    double err[2] = {};
    for (int k = 0; k < 2; ++k) {
      const std::int64_t step = kFrameNs >> k;
      net::PartnerPoseBuffer buf;
      buf.push(frame(space, 1, 0), 0);
      buf.push(frame(space, 2, step), step);
      err[k] = max_diff(buf.at(step / 2).pose[0], walking(space, 0.5e-9 * static_cast<double>(step)));
    }
    // In E3 a translation and a turn about a fixed axis blend exactly (the
    // error left is the half nanosecond of an odd step).
    if (kind == SpaceKind::E3)
      EXPECT_LT(err[0], 1e-9);
    else
      EXPECT_GT(err[0] / err[1], 3.5) << to_string(kind) << ": " << err[0] << " then " << err[1];
  }
}

TEST(NetPartnerPoses, ADeviceIsTrackedOnlyWhereBothSamplesTrackIt) {
  const Space space{SpaceKind::E3, 1.0};
  net::PartnerPoseBuffer buf;
  auto a = frame(space, 1, 0);
  auto b = frame(space, 2, kFrameNs);
  a.tracked = 0b0011;
  a.pose[1] = walking(space, 0.0);
  b.tracked = 0b0001;
  buf.push(a, 0);
  buf.push(b, kFrameNs);
  EXPECT_EQ(buf.at(kFrameNs / 2).tracked, 0b0001);
}

TEST(NetPartnerPoses, OldOrRepeatedFramesAreIgnored) {
  const Space space{SpaceKind::H3, 1.0};
  net::PartnerPoseBuffer buf;
  buf.push(frame(space, 5, 5 * kFrameNs), 5 * kFrameNs);
  buf.push(frame(space, 4, 4 * kFrameNs), 4 * kFrameNs);
  buf.push(frame(space, 5, 6 * kFrameNs), 6 * kFrameNs);
  EXPECT_EQ(buf.size(), 1u);
  EXPECT_FALSE(net::PartnerPoseBuffer().at(0).valid);
}
