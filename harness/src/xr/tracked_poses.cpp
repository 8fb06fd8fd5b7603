#include "curvlab/harness/xr/tracked_poses.hpp"

#include "curvlab/harness/xr/stereo.hpp"

#include <iostream>
#include <utility>
#include <vector>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;

namespace {

bool located(XrSpaceLocationFlags flags) {
  // Valid and tracked: an inferred (untracked) pose counts as lost tracking,
  // which is data (DESIGN.md §3), not a pose to show.
  constexpr XrSpaceLocationFlags want =
      XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT |
      XR_SPACE_LOCATION_POSITION_TRACKED_BIT | XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT;
  return (flags & want) == want;
}

// The orientation alone valid and tracked, as a 3-DoF device or one that
// lost its position reports it.
bool orientation_located(XrSpaceLocationFlags flags) {
  constexpr XrSpaceLocationFlags want =
      XR_SPACE_LOCATION_ORIENTATION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT;
  return (flags & want) == want;
}

// Valid, perhaps inferred: a pose the runtime says can be used. The head's
// is used so; whether its tracking is good enough for a trial is the
// protocol's [tracking] head_requires (a headset without positional
// tracking, or Monado's simulated one, infers the position).
bool usable(XrSpaceLocationFlags flags) {
  constexpr XrSpaceLocationFlags want = XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
  return (flags & want) == want;
}

// The flags by their names in the specification, for messages.
std::string location_flags_text(XrSpaceLocationFlags flags) {
  std::string out;
  for (const auto& [bit, name] : {std::pair{XR_SPACE_LOCATION_ORIENTATION_VALID_BIT, "ORIENTATION_VALID"},
                                  std::pair{XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT, "ORIENTATION_TRACKED"},
                                  std::pair{XR_SPACE_LOCATION_POSITION_VALID_BIT, "POSITION_VALID"},
                                  std::pair{XR_SPACE_LOCATION_POSITION_TRACKED_BIT, "POSITION_TRACKED"}}) {
    out += out.empty() ? "" : " | ";
    out += (flags & bit) != 0 ? name : std::string("no ") + name;
  }
  return out;
}

}  // namespace

Result<std::unique_ptr<TrackedPoses>> TrackedPoses::create(Session& session, const Controllers& controllers) {
  std::unique_ptr<TrackedPoses> p(new TrackedPoses(session));
  // The combined gaze's action set and binding must be suggested before
  // the attach.
  auto eyes = EyeTracking::create(session.instance(), session.system(), session.gaze_extensions());
  if (!eyes) return eyes.error();
  p->eyes_.emplace(std::move(eyes).value());
  if (auto r = p->make_spaces(controllers); !r) return r.error();
  session.join(*p);
  return p;
}

TrackedPoses::~TrackedPoses() { session_.leave(*this); }

// The STAGE and VIEW reference spaces, and a grip space per hand once the
// action sets are attached.
Result<Done> TrackedPoses::make_spaces(const Controllers& controllers) {
  const XrSession session = session_.handle();
  auto space_info = tagged<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
  space_info.poseInReferenceSpace = kIdentityPose;
  space_info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
  if (const XrResult r = xrCreateReferenceSpace(session, &space_info, stage_.out()); XR_FAILED(r))
    return Error{Error::Kind::device,
                 failure_of(r, "xrCreateReferenceSpace").message +
                     " (STAGE space: set up the play area / room boundary in the runtime, so "
                     "that the floor and the table are where curvlab's lab frame says)"};
  space_info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_VIEW;
  if (const XrResult r = xrCreateReferenceSpace(session, &space_info, view_.out()); XR_FAILED(r))
    return failure_of(r, "xrCreateReferenceSpace");

  // Attached once, all together: curvlab's and the eye gaze's.
  std::vector<XrActionSet> action_sets{controllers.action_set()};
  if (eyes_->action_set() != XR_NULL_HANDLE) action_sets.push_back(eyes_->action_set());
  if (auto r = session_.attach(action_sets); !r) return r;
  if (auto r = eyes_->start(session); !r) return r;
  for (std::size_t i = 0; i < 2; ++i) {
    auto info = tagged<XrActionSpaceCreateInfo>(XR_TYPE_ACTION_SPACE_CREATE_INFO);
    info.action = controllers.action("grip_pose");
    info.subactionPath = controllers.hand(i);
    info.poseInActionSpace = kIdentityPose;
    if (const XrResult r = xrCreateActionSpace(session, &info, grip_[i].out()); XR_FAILED(r))
      return failure_of(r, "xrCreateActionSpace");
  }
  return Done{};
}

void TrackedPoses::on_event(const XrEventDataBuffer& event) {
  if (event.type == XR_TYPE_EVENT_DATA_REFERENCE_SPACE_CHANGE_PENDING)
    on_stage_change(*reinterpret_cast<const XrEventDataReferenceSpaceChangePending*>(&event));
}

// The runtime moves STAGE's origin (a redrawn play area or boundary): from
// changeTime on its poses are in the new origin. The room and the table did
// not move, and the table's calibration is in the lab frame (the STAGE
// before the move), so where the runtime says where the new origin lies,
// curvlab keeps the lab frame: it locates in a STAGE space offset by the
// inverse of the move, from the first frame displayed at or after
// changeTime. Where the runtime does not know the move, the table may have
// moved under the participant: the attempt is dropped (recenter) and the
// experimenter told to check the calibration.
void TrackedPoses::on_stage_change(const XrEventDataReferenceSpaceChangePending& e) {
  if (e.referenceSpaceType != XR_REFERENCE_SPACE_TYPE_STAGE) return;
  harness::io::DisplayReport report;
  report.kind = harness::io::DisplayReport::Kind::stage_moved;
  report.change_ns = session_.to_session_ns(e.changeTime);
  report.pose_valid = e.poseValid == XR_TRUE;
  const XrPosef& p = e.poseInPreviousSpace;
  report.origin = {p.position.x, p.position.y, p.position.z, p.orientation.x, p.orientation.y, p.orientation.z,
                   p.orientation.w};
  if (const auto offset = anchor_.offset_after(report.pose_valid, p)) {
    auto info = tagged<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
    info.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_STAGE;
    info.poseInReferenceSpace = *offset;
    SpaceHandle next;
    if (const XrResult r = xrCreateReferenceSpace(session_.handle(), &info, next.out()); XR_SUCCEEDED(r)) {
      stage_next_ = std::move(next);
      anchor_.schedule(*offset, e.changeTime);
      report.kept_lab_frame = true;
    } else if (fatal(r)) {
      session_.fail(r, "xrCreateReferenceSpace");
    }
  }
  if (report.kept_lab_frame) {
    std::cerr << "curvlab: xr: the runtime moved its STAGE origin (a new play area or boundary) by (" << p.position.x
              << ", " << p.position.y << ", " << p.position.z
              << ") m; curvlab keeps the lab frame where it was, so the table calibration still holds\n";
  } else {
    std::cerr << "curvlab: xr: the runtime moved its STAGE origin (a new play area or boundary) without saying "
                 "where; the trial is run again: check that the table is where the participant sees it, and "
                 "calibrate again (curvlab calibrate) if not\n";
    session_.signal(harness::io::Signal::recenter);
  }
  session_.report(report);
}

void TrackedPoses::follow_stage_change(XrTime display_time) {
  if (!anchor_.due(display_time)) return;
  stage_ = std::move(stage_next_);
  anchor_.follow();
}

std::pair<StagePose, XrSpaceLocationFlags> TrackedPoses::locate_space(XrSpace space, XrTime t) {
  auto loc = tagged<XrSpaceLocation>(XR_TYPE_SPACE_LOCATION);
  const XrResult r = xrLocateSpace(space, stage_.get(), t, &loc);
  if (fatal(r)) session_.fail(r, "xrLocateSpace");
  return {to_stage_pose(loc.pose), XR_SUCCEEDED(r) ? loc.locationFlags : XrSpaceLocationFlags{0}};
}

void TrackedPoses::locate(XrTime t) {
  const auto [head, head_flags] = locate_space(view_.get(), t);
  head_ = head;
  head_flags_ = head_flags;
  lab_[geometry::Device::head] = to_geometry(head, usable(head_flags));
  for (std::size_t i = 0; i < 2; ++i) {
    const auto [hand, hand_flags] = locate_space(grip_[i].get(), t);
    auto& pose = lab_[i == 0 ? geometry::Device::left_hand : geometry::Device::right_hand];
    pose = to_geometry(hand, located(hand_flags));
    pose.orientation_valid = orientation_located(hand_flags);
  }
  gaze_.reset();
  if (eyes_->any()) {
    auto found = eyes_->locate(stage_.get(), t, head);
    if (found.fatal != XR_SUCCESS) session_.fail(found.fatal, found.call);
    gaze_ = std::move(found.gaze);
  }
}

void TrackedPoses::lose_tracking() {
  head_flags_ = 0;
  for (auto& pose : lab_.pose) pose.valid = false;
  gaze_.reset();
}

geometry::LabFrame TrackedPoses::poses(const harness::io::FrameTiming& frame) {
  (void)frame;  // located in locate() at this frame's predicted display time
  return lab_;
}

harness::io::HeadTracking TrackedPoses::head_tracking() const {
  return {(head_flags_ & XR_SPACE_LOCATION_ORIENTATION_TRACKED_BIT) != 0,
          (head_flags_ & XR_SPACE_LOCATION_POSITION_TRACKED_BIT) != 0};
}

std::string TrackedPoses::describe_head_tracking() const {
  return location_flags_text(head_flags_) + " (xrLocateSpace of the VIEW space)";
}

}  // namespace curvlab::harness::xr
