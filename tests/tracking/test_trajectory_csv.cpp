// Trajectory CSV: lossless round trip, and errors that name file, line,
// column and field.
#include "curvlab/harness/tracking/trajectory_csv.hpp"

#include <gtest/gtest.h>

#include <sstream>

namespace {

using namespace curvlab::geometry;
using curvlab::harness::TrajectoryFile;

curvlab::harness::Result<TrajectoryFile> parse(const std::string& text) {
  std::istringstream in(text);
  return curvlab::harness::parse_trajectory_csv(in, "t.csv");
}

std::string error_of(const std::string& text) {
  auto r = parse(text);
  if (!r) return r.error().message;
  return "(no error)";
}

std::string row(const std::string& t, const std::string& head_qw = "1", const std::string& valid = "1") {
  return t + "," + valid + ",0,1.6,0.8," + head_qw + ",0,0,0,1,-0.25,0.78,0.45,1,0,0,0,1,0.25,0.78,0.45,1,0,0,0\n";
}

TEST(TrajectoryCsv, RoundTripIsLossless) {
  PhysicalTable table;
  table.yaw_rad = 0.1234567890123;
  table.edge_m = 0.87;
  WalkAroundOptions o;
  o.common.table = table;
  o.laps = 0.3;
  const Trajectory t = walk_around(o);
  std::stringstream ss;
  curvlab::harness::write_trajectory_csv(ss, t, table);
  auto r = curvlab::harness::parse_trajectory_csv(ss, "mem");
  ASSERT_TRUE(r) << r.error().message;
  const auto& f = r.value();
  EXPECT_TRUE(f.table_given);
  EXPECT_EQ(f.table.yaw_rad, table.yaw_rad);
  EXPECT_EQ(f.table.edge_m, table.edge_m);
  ASSERT_EQ(f.samples.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(f.samples[i].t_ns, t[i].t_ns);
    for (std::size_t d = 0; d < 3; ++d) {
      EXPECT_EQ(f.samples[i].frame.pose[d].position_m, t[i].frame.pose[d].position_m);
      EXPECT_EQ(f.samples[i].frame.pose[d].orientation, t[i].frame.pose[d].orientation);
    }
  }
}

TEST(TrajectoryCsv, ErrorsNameLineColumnAndField) {
  const std::string h = curvlab::harness::trajectory_csv_header() + "\n";
  EXPECT_EQ(error_of(h + row("0") + row("11111111", "abc")).rfind("t.csv:3:", 0), 0u);
  EXPECT_NE(error_of(h + row("0") + row("11111111", "abc")).find("field 'head_qw': expected a finite number, got 'abc'"),
            std::string::npos);
  // Column of head_qw: "11111111,1,0,1.6,0.8," is 21 characters.
  EXPECT_NE(error_of(h + row("11111111", "abc")).find("t.csv:2:22:"), std::string::npos);
  EXPECT_NE(error_of(h + row("5") + row("5")).find("field 't_ns': expected a time after"), std::string::npos);
  EXPECT_NE(error_of(h + row("0", "2")).find("unit quaternion"), std::string::npos);
  EXPECT_NE(error_of(h + row("0", "1", "yes")).find("field 'head_valid'"), std::string::npos);
  EXPECT_NE(error_of("t_ns,head_valid\n").find("t.csv:1:"), std::string::npos);
  EXPECT_NE(error_of(h + "0,1,2\n").find("expected 25 fields, got 3"), std::string::npos);
  EXPECT_NE(error_of("# physical_table edge_m=x\n" + h + row("0")).find("t.csv:1:"), std::string::npos);
  EXPECT_NE(error_of(h).find("at least one data row"), std::string::npos);
}

TEST(TrajectoryCsv, LostDevicesMayCarryNoPose) {
  const std::string h = curvlab::harness::trajectory_csv_header() + "\n";
  auto r = parse(h + "0,0,,,,,,,,1,-0.25,0.78,0.45,1,0,0,0,0,nan,nan,nan,nan,nan,nan,nan\n");
  ASSERT_TRUE(r) << r.error().message;
  const auto& f = r.value();
  EXPECT_FALSE(f.samples[0].frame[Device::head].valid);
  EXPECT_TRUE(f.samples[0].frame[Device::left_hand].valid);
  EXPECT_FALSE(f.samples[0].frame[Device::right_hand].valid);
}

}  // namespace
