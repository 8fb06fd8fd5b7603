#include "helpers.hpp"

#include "curvlab/geometry/holonomy.hpp"
#include "curvlab/geometry/maps.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tube.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include <numbers>

namespace curvlab::testing {
namespace {

using namespace geometry;
constexpr double kPi = std::numbers::pi;

TableShape table_or_fail(SpaceKind kind, double edge, int sides, double e3_rho = 1.0) {
  auto r = right_angled_table_from_edge(kind, edge, sides, e3_rho);
  if (auto* e = std::get_if<GeometryError>(&r)) ADD_FAILURE() << e->message;
  return std::get<TableShape>(r);
}

TEST(Table, S3TriangleHasSideHalfPi) {
  const TableShape t = table_or_fail(SpaceKind::S3, 0.9, 3);
  EXPECT_NEAR(t.side_rad, oracle::to_d(acosq(oracle::Q(0))), 1e-15);
  EXPECT_NEAR(t.radius_m, 0.9 / oracle::to_d(acosq(oracle::Q(0))), 1e-15);
  EXPECT_DOUBLE_EQ(t.physical_laps_per_virtual_lap(), 0.75);
}

TEST(Table, H3PentagonHasSideAcoshOfTheGoldenRatio) {
  const TableShape t = table_or_fail(SpaceKind::H3, 0.9, 5);
  const oracle::Q phi = (1 + sqrtq(5)) / 2;
  EXPECT_NEAR(t.side_rad, oracle::to_d(acoshq(phi)), 1e-15);
  EXPECT_DOUBLE_EQ(t.physical_laps_per_virtual_lap(), 1.25);
}

TEST(Table, E3SquareTakesItsSideFromTheRadius) {
  const TableShape t = table_or_fail(SpaceKind::E3, 0.9, 4, 2.0);
  EXPECT_DOUBLE_EQ(t.side_rad, 0.45);
  EXPECT_DOUBLE_EQ(t.physical_laps_per_virtual_lap(), 1.0);
  EXPECT_NEAR(t.circumradius_m(), 0.9 / std::sqrt(2.0), 1e-15);
  EXPECT_NEAR(t.apothem_m(), 0.45, 1e-15);
}

TEST(Table, ImpossibleTablesAreRefusedWithAReason) {
  for (auto [kind, n] : {std::pair{SpaceKind::S3, 4}, {SpaceKind::E3, 5}, {SpaceKind::H3, 4}}) {
    auto r = right_angled_table_from_edge(kind, 0.9, n);
    ASSERT_TRUE(std::holds_alternative<GeometryError>(r));
    EXPECT_NE(std::get<GeometryError>(r).message.find("90°"), std::string::npos);
  }
  EXPECT_TRUE(std::holds_alternative<GeometryError>(right_angled_table_from_edge(SpaceKind::H3, -1.0, 5)));
}

TEST(Table, CornersAreRightAngledAndEdgesHaveThePhysicalLength) {
  for (auto [kind, n] : {std::pair{SpaceKind::S3, 3}, {SpaceKind::E3, 4}, {SpaceKind::H3, 5},
                         {SpaceKind::H3, 6}, {SpaceKind::H3, 8}}) {
    const TableShape t = table_or_fail(kind, 0.9, n);
    const Space s{kind, t.radius_m};
    for (int j = 0; j < n; ++j) {
      const Point a = table_corner(s, t, j);
      const Point b = table_corner(s, t, j + 1);
      const Point prev = table_corner(s, t, j - 1);
      EXPECT_LT(off_space_error(s, a), 1e-14);
      EXPECT_NEAR(a.y, 0.0, 1e-15);  // the table lies in the horizontal plane
      const double edge = oracle::to_d(oracle::distance(to_oracle(kind), to_q(a), to_q(b), s.radius_m)) * s.radius_m;
      EXPECT_NEAR(edge, 0.9, 1e-13) << to_string(kind) << " n=" << n;
      // Angle at corner a between the edges toward b and toward prev.
      const Isometry at_a = translation_to(s, a);
      const Vec3 to_b = log_at(s, at_a, b);
      const Vec3 to_prev = log_at(s, at_a, prev);
      const double angle = std::acos(glm::dot(to_b, to_prev) / (glm::length(to_b) * glm::length(to_prev)));
      EXPECT_NEAR(angle, kPi / 2.0, 1e-12) << to_string(kind) << " n=" << n;
    }
    // Circumradius and apothem agree with the corners and edge midpoints.
    EXPECT_NEAR(distance_m(s, origin(s), table_corner(s, t, 0)), t.circumradius_m(), 1e-13);
    const Point mid = position(s, table_edge_frame(s, t, 2, 0.45));
    EXPECT_NEAR(distance_m(s, origin(s), mid), t.apothem_m(), 1e-13);
  }
}

TEST(Table, EdgeFramesRunCounterClockwiseWithZOutward) {
  const TableShape t = table_or_fail(SpaceKind::H3, 0.9, 5);
  const Space s{SpaceKind::H3, t.radius_m};
  const Isometry f = table_edge_frame(s, t, 0, 0.45);
  const Point mid = position(s, f);
  EXPECT_GT(mid.z, 0.0);              // edge 0 faces +z
  EXPECT_NEAR(mid.x, 0.0, 1e-15);
  EXPECT_GT(f.m[0].x, 0.99);          // x along the edge, toward +x (ccw from above)
  EXPECT_GT(f.m[2].z, 0.99);          // z outward
  // The end of edge 0 is the start of edge 1.
  const Point end0 = position(s, table_edge_frame(s, t, 0, 0.9));
  const Point start1 = position(s, table_edge_frame(s, t, 1, 0.0));
  EXPECT_LT(glm::length(end0 - start1), 1e-14);
}

TEST(Tube, FermiOffsetsAreGeodesicDistancesFromTheAxis) {
  Rng rng(20);
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 0.6};
    const Isometry axis = random_isometry(s, rng, 1.0);
    for (int i = 0; i < 50; ++i) {
      const double along = rng.uniform(-0.5, 0.5);
      const double oy = rng.uniform(-0.05, 0.05);
      const double oz = rng.uniform(-0.05, 0.05);
      const Point p = fermi_point(s, axis, along, oy, oz);
      const Point foot = fermi_point(s, axis, along, 0.0, 0.0);
      const double d = oracle::to_d(oracle::distance(to_oracle(kind), to_q(foot), to_q(p), s.radius_m)) * s.radius_m;
      EXPECT_NEAR(d, std::hypot(oy, oz), 1e-13);
    }
  }
}

TEST(Tube, BentStickSagittaIsTheMidpointOffsetAndStraightStickIsAGeodesic) {
  for (SpaceKind kind : kAllKinds) {
    const Space s{kind, 0.7};
    const Isometry frame = translation_m(s, Vec3(0, 0, -1.0));
    BentStick bent{1.0, 0.03, 0.0125};
    const Point chord_mid = position(s, frame);
    EXPECT_NEAR(distance_m(s, chord_mid, bent.centre_point(s, frame, 0.0)), 0.03, 1e-14);
    EXPECT_NEAR(bent.offset_m(0.5), 0.0, 1e-16);
    BentStick straight{1.0, 0.0, 0.0125};
    const Point a = straight.centre_point(s, frame, -0.5);
    const Point b = straight.centre_point(s, frame, 0.5);
    const Point m = straight.centre_point(s, frame, 0.1);
    EXPECT_NEAR(distance_m(s, a, m) + distance_m(s, m, b), distance_m(s, a, b), 1e-13);
  }
}

TEST(HeadSquare, MatchesTheProductOfThePapersMatricesInQuadPrecision) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3}) {
    for (double theta : {1e-3, 0.01, 0.1, 0.3, 0.7}) {
      const Space s{kind, 1.0};
      const auto k = to_oracle(kind);
      // forward (−z), left (−x), back (+z), right (+x), each in the head frame.
      const auto m = oracle::mul(oracle::mul(oracle::axis_translation(k, 2, -theta),
                                             oracle::axis_translation(k, 0, -theta)),
                                 oracle::mul(oracle::axis_translation(k, 2, theta),
                                             oracle::axis_translation(k, 0, theta)));
      const HolonomyResult h = head_square(s, theta);
      EXPECT_LT(max_diff(h.final_pose, m), 1e-15);
      // Offset: the oracle's distance from the origin of the final position.
      oracle::QVec4 o;
      o[3] = 1;
      EXPECT_NEAR(h.offset_rad, oracle::to_d(oracle::distance_from_origin(k, oracle::mul(m, o), 1)),
                  1e-15 + 1e-13 * h.offset_rad);
    }
  }
}

TEST(HeadSquare, RotationIsThetaSquaredWithTheSignOfCurvatureAndOffsetThetaCubedOverRoot2) {
  for (SpaceKind kind : {SpaceKind::S3, SpaceKind::H3}) {
    const Space s{kind, 1.0};
    for (double theta : {1e-3, 3e-3, 0.01, 0.03, 0.1}) {
      const HolonomyResult h = head_square(s, theta);
      const double t2 = theta * theta;
      EXPECT_NEAR(h.rotation_rad / (s.k() * t2), 1.0, 2.0 * t2) << to_string(kind) << " " << theta;
      EXPECT_NEAR(h.offset_rad / (t2 * theta / std::sqrt(2.0)), 1.0, 2.0 * t2 + 1e-6);
    }
    // In E3 the square closes exactly.
    const HolonomyResult flat = head_square(Space{SpaceKind::E3, 1.0}, 0.2);
    EXPECT_LT(max_diff(flat.final_pose, Isometry::identity()), 1e-16);
  }
}

}  // namespace
}  // namespace curvlab::testing

// A table top's bulge as a viewer reads it from perceived points: a regular
// pentagon in a tilted plane, its centre raised by a known height along the
// plane's normal; the height comes back, signed by the side `up` points to.
TEST(TableTop, HeightAboveTheRimIsTheRaiseAlongThePlaneNormal) {
  using curvlab::geometry::height_above_rim;
  using Vec3 = glm::dvec3;
  const glm::dmat3 tilt = glm::dmat3(glm::rotate(glm::dmat4(1.0), 0.4, glm::dvec3(1.0, 0.3, -0.2)));
  const Vec3 origin(0.2, 1.1, -1.5);
  std::vector<Vec3> rim;
  for (int k = 0; k < 5; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 5.0;
    rim.push_back(origin + tilt * Vec3(0.6 * std::cos(a), 0.0, 0.6 * std::sin(a)));
  }
  const Vec3 up = tilt * Vec3(0.0, 1.0, 0.0);
  for (const double h : {0.012, -0.004, 0.0}) {
    const Vec3 centre = origin + h * up;
    EXPECT_NEAR(height_above_rim(rim, centre, up), h, 1e-12) << h;
    EXPECT_NEAR(height_above_rim(rim, centre, -up), -h, 1e-12) << h;
    std::vector<Vec3> reversed(rim.rbegin(), rim.rend());  // the rim's order does not matter
    EXPECT_NEAR(height_above_rim(reversed, centre, up), h, 1e-12) << h;
  }
  EXPECT_EQ(height_above_rim({origin, origin, origin}, origin + up, up), 0.0) << "a rim with no area";
}
