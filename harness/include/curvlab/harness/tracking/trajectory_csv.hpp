// Trajectory files: timed lab poses of head and hands as CSV (format in
// docs/tracking.md), and the per-frame output of a tracker as CSV. File
// formats live here, apart from the algorithms in geometry/.
#pragma once

#include "curvlab/geometry/tracking.hpp"
#include "curvlab/geometry/trajectory.hpp"
#include "curvlab/harness/result.hpp"

#include <iosfwd>
#include <optional>
#include <string>

namespace curvlab::harness {

struct TrajectoryFile {
  geometry::Trajectory samples;
  // From the optional "# physical_table …" line; the default table otherwise.
  geometry::PhysicalTable table;
  bool table_given = false;
};

// The CSV header row (25 columns: t_ns, then valid, x, y, z, qw, qx, qy, qz per device).
const std::string& trajectory_csv_header();

// A problem a person must fix in the file is an Error of kind bad_input whose
// message names file:line:column, the field and what was expected; a file
// that cannot be opened is not_found.
Result<TrajectoryFile> parse_trajectory_csv(std::istream& in, const std::string& name);
Result<TrajectoryFile> read_trajectory_csv(const std::string& path);

// Writes the format read above (17 significant digits: lossless for doubles).
void write_trajectory_csv(std::ostream& out, const geometry::Trajectory& trajectory,
                          const geometry::PhysicalTable& table);

// Per-frame tracker output: time, state, coherence of each hand and the
// three 4×4 isometries (row-major, dimensionless).
const std::string& tracking_csv_header();
void write_tracking_csv_row(std::ostream& out, std::int64_t t_ns,
                            const geometry::TrackingOutput& frame);

}  // namespace curvlab::harness
