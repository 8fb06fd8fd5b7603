#include "curvlab/geometry/tracking.hpp"

#include "curvlab/geometry/enum_names.hpp"
#include "curvlab/geometry/maps.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace curvlab::geometry {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kHead = 0;

int wrap_index(std::int64_t i, int n) {
  return static_cast<int>(((i % n) + n) % n);
}

// x wrapped into [−period/2, period/2).
double wrap_centred(double x, double period) {
  return x - period * std::floor(x / period + 0.5);
}

// The signed number of counter-clockwise edge steps from edge `from` to edge
// `to` of the square, choosing among the equivalent steps (mod 4) the one
// closest to the signed perimeter displacement du (in edges). This is the
// "nearest signed edge offset": it follows the short way round the table.
int signed_edge_step(int from, int to, double du) {
  const int raw = ((to - from) % 4 + 4) % 4;
  return std::abs(raw - du) <= std::abs(raw - 4 - du) ? raw : raw - 4;
}

Vec3 rotate_y(double angle_rad, const Vec3& v) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  return {c * v.x + s * v.z, v.y, -s * v.x + c * v.z};
}

Mat3 rotation_y(double angle_rad) {
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  Mat3 r(1.0);
  r[0] = Vec3(c, 0.0, -s);  // column x
  r[2] = Vec3(s, 0.0, c);   // column z
  return r;
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

void measure(const RigidPose& felt, const RigidPose& seen, double* err_m, double* err_rad) {
  *err_m = glm::length(seen.translation_m - felt.translation_m);
  *err_rad = rotation_angle_rad(glm::transpose(seen.rotation) * felt.rotation);
}

}  // namespace

std::string_view to_string(Device device) {
  switch (device) {
    case Device::head: return "head";
    case Device::left_hand: return "left_hand";
    case Device::right_hand: return "right_hand";
  }
  return "?";
}

std::string_view to_string(TrackingAlgorithm algorithm) {
  switch (algorithm) {
    case TrackingAlgorithm::naive: return "naive";
    case TrackingAlgorithm::head_anchored: return "head-anchored";
    case TrackingAlgorithm::table_anchored: return "table-anchored";
  }
  return "?";
}

std::optional<TrackingAlgorithm> parse_tracking_algorithm(std::string_view text) {
  return parse_name(kTrackingAlgorithms, text);
}

bool usable(const LabPose& pose) {
  if (!pose.valid || !finite(pose.position_m)) return false;
  const Quat& q = pose.orientation;
  const double n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  return std::isfinite(n2) && std::abs(std::sqrt(n2) - 1.0) <= 1e-3;
}

RigidPose rigid_from_lab(const LabPose& pose) {
  return {glm::mat3_cast(glm::normalize(pose.orientation)), pose.position_m};
}

Isometry curved_from_rigid(const Space& space, const RigidPose& pose) {
  return translation_m(space, pose.translation_m) * rotation(pose.rotation);
}

RigidPose rigid_reading(const Space& space, const Isometry& iso) {
  // The same split as decompose() (M = T·R, T the translation to M's
  // position), but every frame reads four of these, so T⁻¹ is built from the
  // position column itself (C(t) = w, S(t) = |xyz|, both already divided by
  // ρ) and the only transcendental call is the one for the distance.
  const Vec4 p = iso.m[3];
  const Vec3 xyz(p.x, p.y, p.z);
  const double r = glm::length(xyz);
  if (!(r > 1e-300)) {
    if (p.w > 0.0) return {Mat3(iso.m), Vec3(0.0)};
    const Decomposition d = decompose(space, iso);  // S3 antipode: no direction
    return {d.rotation, log_origin(space, position(space, iso))};
  }
  const Vec3 u = xyz / r;
  const double c = p.w;
  // T⁻¹ is the translation by −t along u: x_u' = C x_u − S w, the rest of xyz
  // unchanged; applied to M's first three columns it leaves R.
  RigidPose out;
  for (int j = 0; j < 3; ++j) {
    const Vec4 col = iso.m[j];
    const Vec3 cx(col.x, col.y, col.z);
    const double along = glm::dot(u, cx);
    // (T⁻¹ col)_xyz = col_xyz + (c − 1)(u·col_xyz) u − r·col_w u
    out.rotation[j] = cx + ((c - 1.0) * along - r * col.w) * u;
  }
  out.translation_m = (space.radius_m * space.arc(r, c)) * u;
  return out;
}

RigidPose PhysicalTable::edge_frame(int edge, double along_m) const {
  const int e = ((edge % 4) + 4) % 4;
  const double turn = yaw_rad + 0.5 * kPi * e;
  const Vec3 local(along_m - 0.5 * edge_m, 0.0, 0.5 * edge_m);
  const Vec3 p = rotate_y(turn, local);
  return {rotation_y(turn), Vec3(centre_x_m + p.x, height_m, centre_z_m + p.z)};
}

Vec3 PhysicalTable::rail_point_m(double perimeter_u) const {
  const double u = perimeter_u - 4.0 * std::floor(perimeter_u / 4.0);
  const int edge = std::min(3, static_cast<int>(u));
  return edge_frame(edge, (u - edge) * edge_m).translation_m;
}

Vec3 PhysicalTable::polar_point_m(double azimuth_rad, double radius_m, double y_m) const {
  const Vec3 p = rotate_y(yaw_rad + azimuth_rad, Vec3(0.0, 0.0, radius_m));
  return {centre_x_m + p.x, y_m, centre_z_m + p.z};
}

PhysicalAnchor physical_anchor(const PhysicalTable& table, const Vec3& position_m) {
  // Into the table's own horizontal frame (undo the yaw).
  const Vec3 local = rotate_y(-table.yaw_rad, Vec3(position_m.x - table.centre_x_m, 0.0,
                                                    position_m.z - table.centre_z_m));
  PhysicalAnchor a;
  a.radial_m = std::hypot(local.x, local.z);
  const double half = 0.5 * table.edge_m;
  const double m = std::max(std::abs(local.x), std::abs(local.z));
  const double scale = m > 0.0 ? half / m : 0.0;
  const double px = local.x * scale;
  const double pz = local.z * scale;
  // Edge e faces Rot_y(e·90°)·(+z); its x axis is Rot_y(e·90°)·(+x).
  if (std::abs(local.z) >= std::abs(local.x)) {
    a.edge = local.z >= 0.0 ? 0 : 2;
    a.along_m = local.z >= 0.0 ? px + half : half - px;
  } else {
    a.edge = local.x > 0.0 ? 1 : 3;
    a.along_m = local.x > 0.0 ? half - pz : pz + half;
  }
  a.along_m = std::clamp(a.along_m, 0.0, table.edge_m);
  return a;
}

Tracker::Tracker(TrackingAlgorithm algorithm, const Space& space, const TableShape& table,
                 const PhysicalTable& physical, const TrackerOptions& options)
    : algorithm_(algorithm), space_(space), table_(table), physical_(physical),
      options_(options) {
  edge_base_.reserve(static_cast<std::size_t>(table.sides));
  for (int e = 0; e < table.sides; ++e)
    edge_base_.push_back(table_edge_frame(space, table, e, 0.0));
}

Isometry Tracker::virtual_edge_frame(int edge, double fraction) const {
  const Isometry& base = edge_base_[static_cast<std::size_t>(wrap_index(edge, table_.sides))];
  return base * translation_rad(space_, Vec3(1.0, 0.0, 0.0), fraction * table_.side_rad);
}

Isometry Tracker::table_placement(int device, const RigidPose& lab) const {
  const AnchorState& a = anchors_[static_cast<std::size_t>(device)];
  const RigidPose anchor = physical_.edge_frame(a.anchor.edge, a.anchor.along_m);
  const RigidPose local = anchor.inverse() * lab;
  return virtual_edge_frame(a.virtual_edge, a.anchor.along_m / physical_.edge_m) *
         curved_from_rigid(space_, local);
}

void Tracker::update_anchor(int device, const Vec3& position_m) {
  AnchorState& s = anchors_[static_cast<std::size_t>(device)];
  const PhysicalAnchor a = physical_anchor(physical_, position_m);
  // Hysteresis: above the centre the ray's direction is meaningless, so the
  // last anchor is held until the device is clearly off centre again. The
  // pose is still placed exactly relative to the held anchor, so the device
  // moves continuously; only the choice of anchor waits.
  if (s.known) {
    const double limit = s.held ? options_.centre_leave_radius_m : options_.centre_enter_radius_m;
    s.held = a.radial_m < limit;
    if (s.held) return;
  }
  s.anchor = a;
  s.known = true;
}

void Tracker::update_correspondence() {
  TrackingState& st = out_.state;
  AnchorState& head = anchors_[kHead];
  const double edge_m = physical_.edge_m;
  const double u = head.anchor.perimeter_u(edge_m);
  if (!st.initialized) {
    st.initialized = true;
    st.physical_edge = head.anchor.edge;
    st.virtual_edge = wrap_index(head.anchor.edge, table_.sides);
    st.physical_edge_unwrapped = st.physical_edge;
    st.virtual_edge_unwrapped = st.virtual_edge;
    start_physical_u_ = u;
    start_virtual_u_ = st.virtual_edge + head.anchor.along_m / edge_m;
  } else if (head.anchor.edge != st.physical_edge) {
    // Step 3: the only history-dependent part. Each physical edge step is the
    // same virtual edge step, in either walking direction.
    const double du = wrap_centred(u - last_head_u_, 4.0);
    int step = signed_edge_step(st.physical_edge, head.anchor.edge, du);
    // Exactly across the table (a lean straight over the centre) both ways
    // round are equally near: take the one that unwinds toward the starting
    // edge, so that leaning over and back restores the correspondence.
    if (std::abs(std::abs(du) - 2.0) < 1e-9) {
      const std::int64_t start_edge = static_cast<std::int64_t>(std::floor(start_physical_u_));
      const std::int64_t here = st.physical_edge_unwrapped;
      const int other = step > 0 ? step - 4 : step + 4;
      if (std::abs(here + other - start_edge) < std::abs(here + step - start_edge)) step = other;
    }
    st.physical_edge = head.anchor.edge;
    st.physical_edge_unwrapped += step;
    st.virtual_edge_unwrapped += step;
    st.virtual_edge = wrap_index(st.virtual_edge_unwrapped, table_.sides);
  }
  last_head_u_ = u;
  head.virtual_edge = st.virtual_edge;
  st.head_over_centre = head.held;
  st.anchor_fraction = head.anchor.along_m / edge_m;
  st.physical_laps =
      (static_cast<double>(st.physical_edge_unwrapped) + st.anchor_fraction - start_physical_u_) / 4.0;
  st.virtual_laps =
      (static_cast<double>(st.virtual_edge_unwrapped) + st.anchor_fraction - start_virtual_u_) /
      table_.sides;
}

const TrackingOutput& Tracker::update(const LabFrame& frame) {
  std::array<bool, kDeviceCount> ok{};
  std::array<RigidPose, kDeviceCount> lab{};
  for (int i = 0; i < kDeviceCount; ++i) {
    const LabPose& p = frame.pose[static_cast<std::size_t>(i)];
    ok[static_cast<std::size_t>(i)] = usable(p);
    if (ok[static_cast<std::size_t>(i)]) lab[static_cast<std::size_t>(i)] = rigid_from_lab(p);
  }
  if (!out_.state.initialized && !ok[kHead]) {
    out_.tracked = {};
    for (auto& c : out_.coherence) c.measured = false;
    return out_;
  }
  if (ok[kHead]) {
    update_anchor(kHead, lab[kHead].translation_m);
    update_correspondence();
  }
  // Hands reuse the head's correspondence (paper, end of "Tracking algorithm
  // for curved-space billiards"): the hand's virtual edge is the head's plus
  // the nearest signed offset between their physical edges. A hand run round
  // the far side therefore jumps once, where that offset flips sign.
  const AnchorState& head = anchors_[kHead];
  const double head_u = head.anchor.perimeter_u(physical_.edge_m);
  for (int h = 1; h < kDeviceCount; ++h) {
    if (!ok[static_cast<std::size_t>(h)]) continue;
    update_anchor(h, lab[static_cast<std::size_t>(h)].translation_m);
    AnchorState& a = anchors_[static_cast<std::size_t>(h)];
    const double du = wrap_centred(a.anchor.perimeter_u(physical_.edge_m) - head_u, 4.0);
    const int offset = signed_edge_step(head.anchor.edge, a.anchor.edge, du);
    a.virtual_edge = wrap_index(out_.state.virtual_edge_unwrapped + offset, table_.sides);
  }
  place(lab, ok);
  if (options_.measure_coherence) {
    measure_coherence(lab, ok);
  } else {
    for (auto& c : out_.coherence) c.measured = false;
  }
  return out_;
}

void Tracker::measure_coherence(const std::array<RigidPose, kDeviceCount>& lab,
                                const std::array<bool, kDeviceCount>& ok) {
  for (int h = 1; h < kDeviceCount; ++h) {
    Coherence& c = out_.coherence[static_cast<std::size_t>(h - 1)];
    const auto hi = static_cast<std::size_t>(h);
    c.measured = ok[kHead] && ok[hi] && out_.tracked[kHead] && out_.tracked[hi];
    if (!c.measured) continue;
    const RigidPose felt = lab[kHead].inverse() * lab[hi];

    const Isometry& vh = out_.pose[kHead];
    const Isometry& vd = out_.pose[hi];
    measure(felt, rigid_reading(space_, inverse(space_, vh) * vd), &c.head_frame_m,
            &c.head_frame_rad);

    const AnchorState& ah = anchors_[kHead];
    const AnchorState& ad = anchors_[hi];
    const double edge_m = physical_.edge_m;
    const Isometry vah = virtual_edge_frame(ah.virtual_edge, ah.anchor.along_m / edge_m);
    const Isometry vad = virtual_edge_frame(ad.virtual_edge, ad.anchor.along_m / edge_m);
    const RigidPose rail = physical_.edge_frame(ah.anchor.edge, ah.anchor.along_m).inverse() *
                           physical_.edge_frame(ad.anchor.edge, ad.anchor.along_m);
    const RigidPose seen = rigid_reading(space_, inverse(space_, vah) * vh).inverse() * rail *
                           rigid_reading(space_, inverse(space_, vad) * vd);
    measure(felt, seen, &c.table_frame_m, &c.table_frame_rad);

    const bool table_ref = algorithm_ == TrackingAlgorithm::table_anchored;
    c.error_m = table_ref ? c.table_frame_m : c.head_frame_m;
    c.error_rad = table_ref ? c.table_frame_rad : c.head_frame_rad;
  }
}

void Tracker::follow_own_motion(std::size_t device, const RigidPose& lab) {
  if (!placed_once_[device]) {
    out_.pose[device] = table_placement(static_cast<int>(device), lab);
    placed_once_[device] = true;
  } else {
    const RigidPose delta = last_lab_[device].inverse() * lab;
    out_.pose[device] = reorthonormalize(space_, out_.pose[device] * curved_from_rigid(space_, delta));
  }
  last_lab_[device] = lab;
}

namespace {

// Naive tracking (paper, "the problem"): every device's motion in its own
// frame since the last frame is applied as the same motion of the curved
// space. Holonomy makes the result depend on the path.
class NaiveTracker final : public Tracker {
 public:
  NaiveTracker(TrackingAlgorithm algorithm, const Space& space, const TableShape& table,
      const PhysicalTable& physical, const TrackerOptions& options)
      : Tracker(algorithm, space, table, physical, options) {}

 private:
  void place(const std::array<RigidPose, kDeviceCount>& lab,
             const std::array<bool, kDeviceCount>& ok) override {
    for (std::size_t i = 0; i < kDeviceCount; ++i) {
      out_.tracked[i] = ok[i];
      if (ok[i]) follow_own_motion(i, lab[i]);
    }
  }
};

// The paper's general algorithm ("General principles") with A = the head:
// ΔA is the head's motion in its own frame since the last frame, applied to
// the virtual head; the hands are placed relative to the head, so what the
// body feels and what the eyes see agree exactly in the head's frame.
class HeadAnchoredTracker final : public Tracker {
 public:
  HeadAnchoredTracker(TrackingAlgorithm algorithm, const Space& space, const TableShape& table,
      const PhysicalTable& physical, const TrackerOptions& options)
      : Tracker(algorithm, space, table, physical, options) {}

 private:
  void place(const std::array<RigidPose, kDeviceCount>& lab,
             const std::array<bool, kDeviceCount>& ok) override {
    if (ok[kHead]) follow_own_motion(kHead, lab[kHead]);
    out_.tracked[kHead] = ok[kHead];
    for (std::size_t h = 1; h < kDeviceCount; ++h) {
      // A hand needs the head in the same frame; otherwise it holds.
      out_.tracked[h] = ok[h] && ok[kHead];
      if (!out_.tracked[h]) continue;
      out_.pose[h] =
          out_.pose[kHead] * curved_from_rigid(space_, lab[kHead].inverse() * lab[h]);
      placed_once_[h] = true;
    }
  }
};

// The billiards algorithm, steps 1–5 (paper, "Tracking algorithm for
// curved-space billiards"): each device is placed relative to its anchor on
// the virtual table edge that corresponds to the physical one. Corners are
// continuous by construction: both tables turn by 90° there, so the two edge
// frames meeting at a corner differ by the same rotation in both.
class TableAnchoredTracker final : public Tracker {
 public:
  TableAnchoredTracker(TrackingAlgorithm algorithm, const Space& space, const TableShape& table,
      const PhysicalTable& physical, const TrackerOptions& options)
      : Tracker(algorithm, space, table, physical, options) {}

 private:
  void place(const std::array<RigidPose, kDeviceCount>& lab,
             const std::array<bool, kDeviceCount>& ok) override {
    for (std::size_t i = 0; i < kDeviceCount; ++i) {
      out_.tracked[i] = ok[i];
      if (!ok[i]) continue;
      out_.pose[i] = table_placement(static_cast<int>(i), lab[i]);
      placed_once_[i] = true;
    }
  }
};

}  // namespace

std::unique_ptr<Tracker> make_tracker(TrackingAlgorithm algorithm, const Space& space,
                                      const TableShape& table, const PhysicalTable& physical,
                                      const TrackerOptions& options) {
  switch (algorithm) {
    case TrackingAlgorithm::naive:
      return std::unique_ptr<Tracker>(new NaiveTracker(algorithm, space, table, physical, options));
    case TrackingAlgorithm::head_anchored:
      return std::unique_ptr<Tracker>(
          new HeadAnchoredTracker(algorithm, space, table, physical, options));
    case TrackingAlgorithm::table_anchored:
      return std::unique_ptr<Tracker>(
          new TableAnchoredTracker(algorithm, space, table, physical, options));
  }
  return nullptr;
}

}  // namespace curvlab::geometry
