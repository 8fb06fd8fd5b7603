// The tracking algorithms driven frame by frame by generated lab
// trajectories, checked against what a participant would notice: which
// virtual edge she stands at, how many laps she made, whether what she feels
// matches what she sees, and where her hand jumps.
#include "curvlab/geometry/holonomy.hpp"
#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/geometry/trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <variant>

namespace {

using namespace curvlab::geometry;

constexpr double kPi = std::numbers::pi;

TableShape table_for(SpaceKind kind, int sides = 0, double edge_m = 0.9) {
  auto r = right_angled_table_from_edge(kind, edge_m, sides > 0 ? sides : default_table_sides(kind));
  return std::get<TableShape>(r);
}

struct RunSummary {
  TrackingOutput first;
  TrackingOutput last;
  double max_error_m = 0.0;
  double max_error_rad = 0.0;
  double max_head_step_m = 0.0;  // largest frame-to-frame virtual head move
  bool all_finite = true;
  std::size_t frames = 0;
};

bool finite(const Isometry& iso) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(iso.m[c][r])) return false;
  return true;
}

RunSummary run(Tracker& tracker, const Trajectory& t) {
  RunSummary s;
  Point last_head{};
  bool have_last = false;
  for (const auto& sample : t) {
    const TrackingOutput& o = tracker.update(sample.frame);
    if (s.frames == 0) s.first = o;
    ++s.frames;
    for (const auto& pose : o.pose) s.all_finite = s.all_finite && finite(pose);
    for (const auto& c : o.coherence) {
      if (!c.measured) continue;
      s.max_error_m = std::max(s.max_error_m, c.error_m);
      s.max_error_rad = std::max(s.max_error_rad, c.error_rad);
    }
    const Point head = position(tracker.space(), o.pose[0]);
    if (have_last) s.max_head_step_m = std::max(s.max_head_step_m, distance_m(tracker.space(), last_head, head));
    last_head = head;
    have_last = true;
  }
  s.last = tracker.output();
  return s;
}

double max_abs_diff(const Isometry& a, const Isometry& b) {
  double m = 0.0;
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) m = std::max(m, std::abs(a.m[c][r] - b.m[c][r]));
  return m;
}

WalkAroundOptions walk(double laps, int direction) {
  WalkAroundOptions o;
  o.laps = laps;
  o.direction = direction;
  return o;
}

// --- edge correspondence and laps -----------------------------------------

TEST(TableAnchored, OneCounterClockwiseLapAdvancesThePentagonByFourEdges) {
  const TableShape table = table_for(SpaceKind::H3);
  auto tracker = make_tracker(TrackingAlgorithm::table_anchored, {SpaceKind::H3, table.radius_m},
                              table, PhysicalTable{});
  const RunSummary s = run(*tracker, walk_around(walk(1.0, +1)));
  EXPECT_EQ(s.first.state.physical_edge, 0);
  EXPECT_EQ(s.first.state.virtual_edge, 0);
  EXPECT_EQ(s.last.state.physical_edge, 0);
  EXPECT_EQ(s.last.state.virtual_edge, 4);
  EXPECT_EQ(s.last.state.virtual_edge_unwrapped - s.first.state.virtual_edge_unwrapped, 4);
  EXPECT_NEAR(s.last.state.physical_laps, 1.0, 1e-12);
  EXPECT_NEAR(s.last.state.virtual_laps, 0.8, 1e-12);
}

struct LapCase {
  SpaceKind kind;
  int sides;
  double physical_laps_per_virtual_lap;
};

class LapsPerVirtualLap : public ::testing::TestWithParam<LapCase> {};

TEST_P(LapsPerVirtualLap, OneVirtualLapReturnsTheHeadToItsVirtualStartingPose) {
  const LapCase c = GetParam();
  const TableShape table = table_for(c.kind, c.sides);
  const Space space{c.kind, table.radius_m};
  auto tracker = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
  const Trajectory t = walk_around(walk(c.physical_laps_per_virtual_lap, +1));
  const RunSummary s = run(*tracker, t);
  EXPECT_NEAR(s.last.state.physical_laps, c.physical_laps_per_virtual_lap, 1e-12);
  EXPECT_NEAR(s.last.state.virtual_laps, 1.0, 1e-12);
  EXPECT_EQ(s.last.state.virtual_edge, s.first.state.virtual_edge);
  // Physically she stands elsewhere (unless the lap count is whole), yet in
  // the curved space she is exactly where she started.
  EXPECT_LT(max_abs_diff(s.last.pose[0], s.first.pose[0]), 1e-12);
  for (int h = 1; h < 3; ++h) EXPECT_LT(max_abs_diff(s.last.pose[h], s.first.pose[h]), 1e-12);
  // No jumps along the way, corners included: the virtual head never moves
  // much more per frame than the lab head (0.5 m/s at 90 Hz ≈ 5.6 mm).
  EXPECT_LT(s.max_head_step_m, 0.02);
  EXPECT_LT(s.max_error_m, 1e-12);
  EXPECT_TRUE(s.all_finite);
}

INSTANTIATE_TEST_SUITE_P(Spaces, LapsPerVirtualLap,
                         ::testing::Values(LapCase{SpaceKind::H3, 5, 1.25},
                                           LapCase{SpaceKind::S3, 3, 0.75},
                                           LapCase{SpaceKind::E3, 4, 1.0},
                                           LapCase{SpaceKind::H3, 6, 1.5},
                                           LapCase{SpaceKind::H3, 7, 1.75}));

TEST(TableAnchored, WalkingBackUnwindsExactly) {
  for (SpaceKind kind : {SpaceKind::H3, SpaceKind::S3, SpaceKind::E3}) {
    const TableShape table = table_for(kind);
    const Space space{kind, table.radius_m};
    auto tracker = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
    Trajectory t = walk_around(walk(2.3, +1));
    WalkAroundOptions back = walk(2.3, -1);
    back.start_azimuth_rad = 2.0 * kPi * 2.3;
    append_trajectory(t, walk_around(back), 90.0);
    // Halfway (after 2.3 laps counter-clockwise) the correspondence has moved on …
    auto mid = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
    const Trajectory out = walk_around(walk(2.3, +1));
    const RunSummary half = run(*mid, out);
    // Laps count the anchor's way round the square's perimeter from the start.
    const PhysicalTable physical;
    const double u_end =
        physical_anchor(physical, out.back().frame[Device::head].position_m).perimeter_u(physical.edge_m);
    EXPECT_NEAR(half.last.state.physical_laps, 2.0 + (u_end - 0.5) / 4.0, 1e-12) << to_string(kind);
    EXPECT_EQ(half.last.state.virtual_edge_unwrapped, 9);  // 2 laps of 4 edges, then one more
    // … and walking back clockwise undoes it, edge by edge.
    const RunSummary s = run(*tracker, t);
    EXPECT_EQ(s.last.state.virtual_edge_unwrapped, s.first.state.virtual_edge_unwrapped)
        << to_string(kind);
    EXPECT_EQ(s.last.state.physical_edge_unwrapped, s.first.state.physical_edge_unwrapped);
    EXPECT_NEAR(s.last.state.virtual_laps, 0.0, 1e-9);
    EXPECT_LT(max_abs_diff(s.last.pose[0], s.first.pose[0]), 1e-9) << to_string(kind);
  }
}

// --- naive tracking and holonomy ------------------------------------------

TEST(Naive, HeadSquareReproducesTheHolonomyOfTheFoundation) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3, SpaceKind::E3}) {
    const TableShape table = table_for(kind);
    const Space space{kind, table.radius_m};
    HeadSquareOptions o;
    o.side_m = 0.30;
    const Trajectory t = head_square(o);
    auto naive = make_tracker(TrackingAlgorithm::naive, space, table, PhysicalTable{});
    const RunSummary s = run(*naive, t);
    const HolonomyResult h = curvlab::geometry::head_square(space, o.side_m / space.radius_m);
    const Isometry expected = s.first.pose[0] * h.final_pose;
    EXPECT_LT(max_abs_diff(s.last.pose[0], expected), 1e-12) << to_string(kind);
    const Decomposition d = decompose(space, inverse(space, s.first.pose[0]) * s.last.pose[0]);
    EXPECT_NEAR(signed_yaw_rad(d.rotation), h.rotation_rad, 1e-12);
    if (kind == SpaceKind::E3) {
      EXPECT_LT(s.max_error_m, 1e-12);
    } else {
      // She sees her still hands offset and rotated by the holonomy.
      EXPECT_GT(s.last.coherence[0].error_rad, 0.5 * std::abs(h.rotation_rad));
      EXPECT_GT(s.last.coherence[0].error_m, 1e-3);
      // The body-anchored algorithm on the same path keeps them where she feels them.
      auto head = make_tracker(TrackingAlgorithm::head_anchored, space, table, PhysicalTable{});
      EXPECT_LT(run(*head, t).max_error_m, 1e-12);
    }
  }
}

// --- coherence over a 10-minute session -----------------------------------

TEST(Coherence, TenMinutesAt90HzStayCoherentForAnchoredAlgorithms) {
  WalkAroundOptions o = walk(0.0, +1);
  o.speed_m_s = 0.5;
  const double circle_m = 2.0 * kPi * (0.45 + o.common.head_distance_m);
  o.laps = 600.0 * o.speed_m_s / circle_m;  // 600 s of walking
  const Trajectory t = walk_around(o);
  ASSERT_GE(t.size(), 54000u);
  ASSERT_GE(t.back().t_ns, 599'000'000'000);
  for (SpaceKind kind : {SpaceKind::H3, SpaceKind::S3}) {
    const TableShape table = table_for(kind);
    const Space space{kind, table.radius_m};
    for (auto algorithm : {TrackingAlgorithm::head_anchored, TrackingAlgorithm::table_anchored}) {
      auto tracker = make_tracker(algorithm, space, table, PhysicalTable{});
      const RunSummary s = run(*tracker, t);
      EXPECT_LE(s.max_error_m, 1e-9) << to_string(kind) << ' ' << to_string(algorithm);
      EXPECT_LE(s.max_error_rad, 1e-9) << to_string(kind) << ' ' << to_string(algorithm);
      EXPECT_TRUE(s.all_finite);
      EXPECT_LT(isometry_error(space, s.last.pose[0]), 1e-12);
    }
    // Naive tracking on the same walk loses coherence: that is the problem
    // the other two solve.
    auto naive = make_tracker(TrackingAlgorithm::naive, space, table, PhysicalTable{});
    EXPECT_GT(run(*naive, t).max_error_m, 0.05) << to_string(kind);
  }
}

TEST(Coherence, EachAlgorithmsOtherReadingShowsItsTradeOff) {
  // Head-anchored keeps the body coherent but drifts against the table; the
  // billiards algorithm keeps every device on the table where it is felt, and
  // in curved space that cannot also be exact in the head's frame.
  const TableShape table = table_for(SpaceKind::H3);
  const Space space{SpaceKind::H3, table.radius_m};
  const Trajectory t = walk_around(walk(1.0, +1));
  auto head = make_tracker(TrackingAlgorithm::head_anchored, space, table, PhysicalTable{});
  auto tab = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
  double head_table = 0.0, tab_head = 0.0;
  for (const auto& s : t) {
    for (const auto& c : head->update(s.frame).coherence) head_table = std::max(head_table, c.table_frame_m);
    for (const auto& c : tab->update(s.frame).coherence) tab_head = std::max(tab_head, c.head_frame_m);
  }
  EXPECT_GT(head_table, 0.05);
  EXPECT_GT(tab_head, 0.01);
}

// --- the mischievous hand -------------------------------------------------

struct HandLapResult {
  int jumps = 0;
  int jump_edge = -1;           // physical edge under the hand at the jump
  double head_drift = 0.0;      // head and left hand must not move at all
  double max_error_m = 0.0;
  double return_error = 0.0;    // right hand back at its starting pose
};

HandLapResult hand_lap_in(SpaceKind kind) {
  const TableShape table = table_for(kind);
  const Space space{kind, table.radius_m};
  auto tracker = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
  const Trajectory t = hand_lap(HandLapOptions{});
  HandLapResult r;
  Isometry head0, left0, right0;
  Point last{};
  const PhysicalTable physical;
  for (std::size_t i = 0; i < t.size(); ++i) {
    const TrackingOutput& o = tracker->update(t[i].frame);
    const Point right = position(space, o.pose[2]);
    if (i == 0) {
      head0 = o.pose[0];
      left0 = o.pose[1];
      right0 = o.pose[2];
    } else {
      // 0.4 m/s at 90 Hz is 4.4 mm per frame; a jump is an edge's worth.
      if (distance_m(space, last, right) > 0.05) {
        ++r.jumps;
        r.jump_edge = physical_anchor(physical, t[i].frame[Device::right_hand].position_m).edge;
      }
    }
    last = right;
    r.head_drift = std::max({r.head_drift, max_abs_diff(o.pose[0], head0), max_abs_diff(o.pose[1], left0)});
    for (const auto& c : o.coherence) r.max_error_m = std::max(r.max_error_m, c.error_m);
  }
  r.return_error = max_abs_diff(tracker->output().pose[2], right0);
  return r;
}

TEST(HandLap, TheHandJumpsOnceOnTheFarSideAndNothingElseHappens) {
  for (SpaceKind kind : {SpaceKind::H3, SpaceKind::S3}) {
    const HandLapResult r = hand_lap_in(kind);
    EXPECT_EQ(r.jumps, 1) << to_string(kind);
    EXPECT_EQ(r.jump_edge, 2) << to_string(kind);  // the edge opposite the head
    EXPECT_EQ(r.head_drift, 0.0);
    EXPECT_LT(r.max_error_m, 1e-12);
    EXPECT_LT(r.return_error, 1e-12);
  }
  // In E3 the virtual table is the physical one: no jump at all.
  EXPECT_EQ(hand_lap_in(SpaceKind::E3).jumps, 0);
}

// --- leaning over the centre ----------------------------------------------

TEST(TableAnchored, LeaningOverTheCentreHoldsTheAnchorAndRestoresOnReturn) {
  for (SpaceKind kind : {SpaceKind::H3, SpaceKind::S3, SpaceKind::E3}) {
    const TableShape table = table_for(kind);
    const Space space{kind, table.radius_m};
    auto tracker = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
    const Trajectory t = lean_over_centre(LeanOverCentreOptions{});
    int over = 0, switches = 0, last_edge = -1;
    bool finite_all = true;
    for (const auto& s : t) {
      const TrackingOutput& o = tracker->update(s.frame);
      over += o.state.head_over_centre ? 1 : 0;
      if (last_edge >= 0 && o.state.physical_edge != last_edge) ++switches;
      last_edge = o.state.physical_edge;
      for (const auto& p : o.pose) finite_all = finite_all && finite(p);
      for (const auto& c : o.coherence) EXPECT_LT(c.error_m, 1e-12);
    }
    EXPECT_GT(over, 0) << to_string(kind);
    EXPECT_EQ(switches, 2) << to_string(kind);  // to the far edge and back, once each
    EXPECT_EQ(tracker->output().state.physical_edge, 0);
    EXPECT_EQ(tracker->output().state.virtual_edge, 0) << to_string(kind);
    EXPECT_EQ(tracker->output().state.virtual_edge_unwrapped, 0) << to_string(kind);
    EXPECT_TRUE(finite_all);
  }
}

TEST(TableAnchored, HysteresisKeepsTheAnchorUntilClearlyOffCentre) {
  const PhysicalTable physical;
  const TableShape table = table_for(SpaceKind::H3);
  auto tracker = make_tracker(TrackingAlgorithm::table_anchored, {SpaceKind::H3, table.radius_m},
                              table, physical);
  LabFrame f;
  auto at = [&](double x, double z) {
    f[Device::head].position_m = Vec3(x, 1.2, z);
    return tracker->update(f).state;
  };
  EXPECT_EQ(at(0.0, 0.8).physical_edge, 0);
  EXPECT_TRUE(at(0.0, 0.05).head_over_centre);
  // 0.12 m off centre toward +x is inside the leave radius (0.15): held.
  TrackingState s = at(0.12, 0.0);
  EXPECT_TRUE(s.head_over_centre);
  EXPECT_EQ(s.physical_edge, 0);
  s = at(0.2, 0.0);
  EXPECT_FALSE(s.head_over_centre);
  EXPECT_EQ(s.physical_edge, 1);
  EXPECT_EQ(s.virtual_edge, 1);
}

// --- lost tracking ---------------------------------------------------------

TEST(LostTracking, HoldsTheLastGoodStateFlaggedAndNeverNaN) {
  const TableShape table = table_for(SpaceKind::H3);
  const Space space{SpaceKind::H3, table.radius_m};
  Trajectory t = walk_around(walk(1.0, +1));
  Trajectory damaged = t;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Frames 0–4: nothing tracked yet. 300–340: head lost. 500–520: right hand
  // reports NaN while flagged valid. 600: a quaternion of norm 2.
  for (int i = 0; i < 5; ++i) damaged[static_cast<std::size_t>(i)].frame[Device::head].valid = false;
  for (int i = 300; i <= 340; ++i) damaged[static_cast<std::size_t>(i)].frame[Device::head].valid = false;
  for (int i = 500; i <= 520; ++i)
    damaged[static_cast<std::size_t>(i)].frame[Device::right_hand].position_m.x = nan;
  damaged[600].frame[Device::left_hand].orientation = Quat(2.0, 0.0, 0.0, 0.0);

  for (auto algorithm : {TrackingAlgorithm::naive, TrackingAlgorithm::head_anchored,
                         TrackingAlgorithm::table_anchored}) {
    auto clean = make_tracker(algorithm, space, table, PhysicalTable{});
    auto tracker = make_tracker(algorithm, space, table, PhysicalTable{});
    Isometry held_head, held_right;
    for (std::size_t i = 0; i < t.size(); ++i) {
      const TrackingOutput ref = clean->update(t[i].frame);
      const TrackingOutput& o = tracker->update(damaged[i].frame);
      for (const auto& p : o.pose) ASSERT_TRUE(finite(p)) << to_string(algorithm) << " frame " << i;
      for (const auto& c : o.coherence) {
        ASSERT_TRUE(std::isfinite(c.error_m));
        ASSERT_TRUE(std::isfinite(c.error_rad));
      }
      if (i < 5) {
        EXPECT_FALSE(o.tracked[0]);
        EXPECT_FALSE(o.state.initialized);
      }
      if (i == 299) held_head = o.pose[0];
      if (i >= 300 && i <= 340) {
        EXPECT_FALSE(o.tracked[0]);
        EXPECT_EQ(max_abs_diff(o.pose[0], held_head), 0.0);
        EXPECT_FALSE(o.coherence[0].measured);
      }
      if (i == 499) held_right = o.pose[2];
      if (i >= 500 && i <= 520) {
        EXPECT_FALSE(o.tracked[2]);
        EXPECT_EQ(max_abs_diff(o.pose[2], held_right), 0.0);
        EXPECT_FALSE(o.coherence[1].measured);
      }
      if (i == 600) {
        EXPECT_FALSE(o.tracked[1]);
      }
      // The table-anchored placement has no memory beyond the edge
      // correspondence, so it is back on the clean run as soon as tracking is.
      if (algorithm == TrackingAlgorithm::table_anchored && i > 345 && o.tracked[2]) {
        EXPECT_LT(max_abs_diff(o.pose[0], ref.pose[0]), 1e-12) << i;
        EXPECT_EQ(o.state.virtual_edge, ref.state.virtual_edge);
      }
    }
  }
}

TEST(PhysicalTableFrames, AnchorsFollowTheEdgeNumbering) {
  PhysicalTable p;
  p.yaw_rad = 0.3;
  p.centre_x_m = 1.0;
  p.centre_z_m = -2.0;
  for (int e = 0; e < 4; ++e) {
    for (double along : {0.1, 0.45, 0.8}) {
      const RigidPose f = p.edge_frame(e, along);
      // A point straight above the rail anchors back to the same place.
      const PhysicalAnchor a = physical_anchor(p, f.translation_m + f.rotation * Vec3(0, 0.5, 0.0));
      EXPECT_EQ(a.edge, e);
      EXPECT_NEAR(a.along_m, along, 1e-12);
      EXPECT_NEAR(glm::length(p.rail_point_m(e + along / p.edge_m) - f.translation_m), 0.0, 1e-12);
    }
  }
}

}  // namespace

namespace {

// The virtual table must turn by exactly 90° at every corner, like the
// physical one, or the billiards algorithm jumps there. Checked for the
// frames the tracker uses and against the S3 octant's apothem,
// acos(√(2/3)) (centre (1,1,1)/√3 to edge midpoint (1,1,0)/√2).
TEST(VirtualTable, CornersTurnByExactlyNinetyDegrees) {
  EXPECT_NEAR(table_for(SpaceKind::S3).apothem_rad, std::acos(std::sqrt(2.0 / 3.0)), 1e-15);
  struct Case { SpaceKind kind; int sides; };
  for (const Case c : {Case{SpaceKind::S3, 3}, Case{SpaceKind::E3, 4}, Case{SpaceKind::H3, 5},
                       Case{SpaceKind::H3, 6}, Case{SpaceKind::H3, 8}}) {
    const TableShape table = table_for(c.kind, c.sides);
    const Space space{c.kind, table.radius_m};
    auto tracker = make_tracker(TrackingAlgorithm::table_anchored, space, table, PhysicalTable{});
    const Isometry turn = rotation(Vec3(0.0, 1.0, 0.0), kPi / 2.0);
    for (int e = 0; e < c.sides; ++e) {
      const Isometry rel = inverse(space, tracker->virtual_edge_frame(e, 1.0)) *
                           tracker->virtual_edge_frame(e + 1, 0.0);
      EXPECT_LT(max_abs_diff(rel, turn), 1e-12) << to_string(c.kind) << " n=" << c.sides << " e=" << e;
    }
  }
}

}  // namespace

namespace {

TEST(RigidReading, InvertsTheCurvedPlacementAndAgreesWithDecompose) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::E3, SpaceKind::H3}) {
    const Space space{kind, 0.7};
    for (const Vec3 t : {Vec3(0.3, -0.5, 0.2), Vec3(0.0, 0.0, 0.0), Vec3(1e-9, 0.0, 0.0),
                         Vec3(-1.1, 0.4, 0.6)}) {
      RigidPose pose;
      pose.rotation = glm::mat3_cast(glm::angleAxis(0.7, glm::normalize(Vec3(1.0, 2.0, -0.5))));
      pose.translation_m = t;
      const Isometry iso = curved_from_rigid(space, pose);
      const RigidPose back = rigid_reading(space, iso);
      EXPECT_LT(glm::length(back.translation_m - t), 1e-12) << to_string(kind);
      const Decomposition d = decompose(space, iso);
      for (int c = 0; c < 3; ++c) {
        EXPECT_LT(glm::length(back.rotation[c] - pose.rotation[c]), 1e-12) << to_string(kind);
        EXPECT_LT(glm::length(back.rotation[c] - d.rotation[c]), 1e-12) << to_string(kind);
      }
    }
  }
}

}  // namespace
