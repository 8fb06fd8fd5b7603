// Body-coherent tracking (paper, "Headset tracking and body coherence: the
// problem" and "… a solution"; DESIGN.md §3): lab poses of the head and both
// hands plus the physical table → isometries of the virtual head and hands in
// the curved space, and the state that links the physical table's edges to
// the virtual table's.
//
// Three algorithms behind one interface (Tracker):
//   naive          each device's local lab motion re-applied as the same local
//                  curved-space motion; shows holonomy.
//   head-anchored  the paper's general algorithm with the head as anchor: the
//                  head moves by the incremental motion ΔA, the hands are
//                  placed relative to the head.
//   table-anchored the billiards algorithm, steps 1–5: every device is placed
//                  relative to its anchor on the table edge; the edge
//                  correspondence is traced through the head's history and
//                  reused for the hands.
//
// Conventions: lab frame x right, y up, −z forward (OpenXR), metres. The
// virtual table is centred at the curved-space origin in the plane y = 0; the
// physical table's top is at height_m, so lab heights are measured from the
// table top.
#pragma once

#include "curvlab/geometry/table.hpp"

#include <glm/gtc/quaternion.hpp>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace curvlab::geometry {

using Quat = glm::dquat;

// One tracked device in the lab: position in metres, unit quaternion, and
// whether the runtime tracked it this frame (lost tracking is data, not an
// error).
struct LabPose {
  Vec3 position_m{0.0};
  Quat orientation{1.0, 0.0, 0.0, 0.0};  // glm order: w, x, y, z
  bool valid = true;  // position and orientation tracked
  // The orientation alone is tracked where `valid` is false: a controller
  // or headset that lost its position but not its orientation (3-DoF).
  bool orientation_valid = false;
};

enum class Device : int { head = 0, left_hand = 1, right_hand = 2 };
inline constexpr int kDeviceCount = 3;
std::string_view to_string(Device device);

struct LabFrame {
  std::array<LabPose, kDeviceCount> pose{};
  LabPose& operator[](Device d) { return pose[static_cast<std::size_t>(d)]; }
  const LabPose& operator[](Device d) const { return pose[static_cast<std::size_t>(d)]; }
};

// A Euclidean rigid motion of the lab: x ↦ rotation·x + translation_m.
struct RigidPose {
  Mat3 rotation{1.0};
  Vec3 translation_m{0.0};

  RigidPose operator*(const RigidPose& rhs) const {
    return {rotation * rhs.rotation, rotation * rhs.translation_m + translation_m};
  }
  [[nodiscard]] RigidPose inverse() const {
    const Mat3 rt = glm::transpose(rotation);
    return {rt, -(rt * translation_m)};
  }
};

// The lab pose as a rigid motion (the quaternion is normalised).
RigidPose rigid_from_lab(const LabPose& pose);

// A lab pose is usable when flagged valid, finite, and its quaternion has a
// norm within 1e-3 of 1 (anything else is treated as lost tracking).
bool usable(const LabPose& pose);

// The rigid motion re-read as a motion of the curved space: translate by the
// tangent vector translation_m (a geodesic of that length, in metres), then
// rotate (paper, step 5: "re-interpreted as rigid motions of the curved
// virtual space"). Exact inverse of rigid_reading for |t| < ρπ in S3.
Isometry curved_from_rigid(const Space& space, const RigidPose& pose);

// An isometry read in geodesic normal coordinates at the origin: the
// azimuthal-equidistant image of its position (metres) and its rotation.
RigidPose rigid_reading(const Space& space, const Isometry& iso);

// The square physical table from calibration. Its edges are numbered like the
// virtual table's (table.hpp): counter-clockwise seen from above, edge 0
// facing +z of the table's own frame, which is the lab rotated by yaw_rad
// about +y around the centre.
struct PhysicalTable {
  double centre_x_m = 0.0;
  double centre_z_m = 0.0;
  double yaw_rad = 0.0;
  double edge_m = 0.90;
  double height_m = 0.75;

  // Frame on edge `edge` (mod 4) at along_m from its first corner, at the
  // table top: x along the edge (counter-clockwise), y up, z outward.
  [[nodiscard]] RigidPose edge_frame(int edge, double along_m) const;
  // The point on the rail (table top, edge line) at perimeter coordinate u
  // (edges: u = edge + along/edge_m, any real, wraps every 4).
  [[nodiscard]] Vec3 rail_point_m(double perimeter_u) const;
  // Lab position of a point given in the table's horizontal polar
  // coordinates (azimuth from the table's +z toward +x, radius, height above
  // the floor).
  [[nodiscard]] Vec3 polar_point_m(double azimuth_rad, double radius_m, double y_m) const;
};

// Step 1 of the billiards algorithm: where the horizontal ray from the table
// centre toward `position_m` crosses the table's edge.
struct PhysicalAnchor {
  int edge = 0;          // 0…3
  double along_m = 0.0;  // 0…edge_m, counter-clockwise
  double radial_m = 0.0; // horizontal distance of the device from the centre
  [[nodiscard]] double perimeter_u(double edge_m) const { return edge + along_m / edge_m; }
};
PhysicalAnchor physical_anchor(const PhysicalTable& table, const Vec3& position_m);

enum class TrackingAlgorithm { naive, head_anchored, table_anchored };
// Every algorithm, in the order protocols and options list them.
inline constexpr std::array kTrackingAlgorithms{TrackingAlgorithm::naive, TrackingAlgorithm::head_anchored,
                                                TrackingAlgorithm::table_anchored};
std::string_view to_string(TrackingAlgorithm algorithm);
std::optional<TrackingAlgorithm> parse_tracking_algorithm(std::string_view text);

struct TrackerOptions {
  // Hysteresis above the table centre, where the anchor ray has no direction:
  // a device whose horizontal distance from the centre falls below
  // enter_radius_m keeps its last anchor (edge and position along it) until
  // it is farther than leave_radius_m again.
  double centre_enter_radius_m = 0.10;
  double centre_leave_radius_m = 0.15;
  // The coherence readings cost about as much as the placement; a frame loop
  // that logs them elsewhere (or a benchmark of placement alone) may skip them.
  bool measure_coherence = true;
};

// The edge correspondence and where the head's anchor is (paper, step 3).
struct TrackingState {
  bool initialized = false;
  int physical_edge = 0;              // 0…3, the edge holding the head's anchor
  int virtual_edge = 0;               // 0…n−1, its virtual counterpart
  std::int64_t physical_edge_unwrapped = 0;  // counter-clockwise steps, signed
  std::int64_t virtual_edge_unwrapped = 0;
  double anchor_fraction = 0.0;       // head anchor's position along its edge, 0…1
  double physical_laps = 0.0;         // signed, counter-clockwise positive, from the start
  double virtual_laps = 0.0;
  bool head_over_centre = false;      // inside the hysteresis zone, anchor held
};

// Felt (lab) versus seen (curved space) pose of one hand relative to the head.
// Two readings of "seen" are computed for every algorithm:
//  - head frame: the virtual hand in geodesic normal coordinates at the
//    virtual head (what the body feels without touching anything);
//  - table frame: head and hand each read in normal coordinates at their
//    virtual anchors on the table edge, joined through the rail, which is
//    locally the same in both tables (what the hands feel through the table).
// `error_m` / `error_rad` is the reading in the algorithm's own reference:
// table frame for table-anchored, head frame for the others.
struct Coherence {
  bool measured = false;  // false when the head or this hand is not tracked
  double error_m = 0.0;
  double error_rad = 0.0;
  double head_frame_m = 0.0;
  double head_frame_rad = 0.0;
  double table_frame_m = 0.0;
  double table_frame_rad = 0.0;
};

struct TrackingOutput {
  std::array<Isometry, kDeviceCount> pose{};
  // true: placed from this frame's lab pose; false: holding the last good
  // pose because the device is not tracked (or never was).
  std::array<bool, kDeviceCount> tracked{};
  std::array<Coherence, 2> coherence{};  // left hand, right hand
  TrackingState state;
};

// The common interface. A tracker owns only fixed-size state (plus the
// virtual table's n edge frames, computed once at construction): update()
// allocates nothing. Not thread-safe; one tracker per participant stream.
class Tracker {
 public:
  virtual ~Tracker() = default;
  Tracker(const Tracker&) = delete;
  Tracker& operator=(const Tracker&) = delete;

  // Advances by one frame. Frames before the first tracked head pose leave
  // every output at the identity with tracked = false.
  const TrackingOutput& update(const LabFrame& frame);
  [[nodiscard]] const TrackingOutput& output() const { return out_; }
  [[nodiscard]] TrackingAlgorithm algorithm() const { return algorithm_; }
  [[nodiscard]] const Space& space() const { return space_; }
  [[nodiscard]] const TableShape& table() const { return table_; }

  // The virtual frame on `edge` (mod n) at fraction f ∈ [0,1] along it.
  [[nodiscard]] Isometry virtual_edge_frame(int edge, double fraction) const;

 protected:
  Tracker(TrackingAlgorithm algorithm, const Space& space, const TableShape& table,
          const PhysicalTable& physical, const TrackerOptions& options);

  // The algorithm's own placement once the correspondence is up to date.
  virtual void place(const std::array<RigidPose, kDeviceCount>& lab,
                     const std::array<bool, kDeviceCount>& ok) = 0;
  // Table-anchored placement of one device with the current correspondence.
  [[nodiscard]] Isometry table_placement(int device, const RigidPose& lab) const;
  // Dead reckoning of one device: placed on the table the first time, then
  // moved by its own lab motion since the last frame, applied in its frame.
  void follow_own_motion(std::size_t device, const RigidPose& lab);

  TrackingAlgorithm algorithm_;
  Space space_;
  TableShape table_;
  PhysicalTable physical_;
  TrackerOptions options_;
  TrackingOutput out_;
  std::array<bool, kDeviceCount> placed_once_{};
  std::array<RigidPose, kDeviceCount> last_lab_{};

  // Per-device anchor, with the hysteresis zone applied.
  struct AnchorState {
    bool known = false;
    bool held = false;  // inside the centre zone
    PhysicalAnchor anchor;
    int virtual_edge = 0;
  };
  std::array<AnchorState, kDeviceCount> anchors_{};

 private:
  void update_anchor(int device, const Vec3& position_m);
  void update_correspondence();
  void measure_coherence(const std::array<RigidPose, kDeviceCount>& lab,
                         const std::array<bool, kDeviceCount>& ok);

  std::vector<Isometry> edge_base_;  // n frames at the first corner of each edge
  double start_physical_u_ = 0.0;
  double start_virtual_u_ = 0.0;
  double last_head_u_ = 0.0;
};

// Builds one of the three algorithms. The virtual table may have any number of
// edges allowed in the space (3 in S3, 4 in E3, ≥ 5 in H3); its edge length
// need not equal the physical one (anchors then correspond by fraction of the
// edge, paper step 4 with equal lengths being the coherent case).
std::unique_ptr<Tracker> make_tracker(TrackingAlgorithm algorithm, const Space& space,
                                      const TableShape& table, const PhysicalTable& physical,
                                      const TrackerOptions& options = {});

}  // namespace curvlab::geometry
