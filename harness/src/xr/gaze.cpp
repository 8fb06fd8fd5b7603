// Eye tracking through OpenXR (xr/gaze.hpp).
#include "curvlab/harness/xr/gaze.hpp"

#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/harness/xr/actions.hpp"
#include "curvlab/harness/xr/fb_eye_tracking_social.hpp"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <utility>

namespace curvlab::harness::xr {

using harness::Done;
using harness::Error;
using harness::Result;

namespace {

// The combined gaze: one pose action without subaction paths, bound to the
// eye gaze interaction profile's only input (XR_EXT_eye_gaze_interaction).
ActionSetDef gaze_action_set() {
  return {.name = "curvlab_gaze",
          .localized_name = "curvlab eye gaze",
          .priority = 0,
          .actions = {{"gaze_pose", "Eye gaze", ActionType::Pose, {}}},
          .profiles = {{kEyeGazeProfile, {{"gaze_pose", kEyeGazePose}}}}};
}

}  // namespace

std::vector<std::string> GazeExtensions::names() const {
  std::vector<std::string> out;
  if (eye_gaze_interaction) out.emplace_back(XR_EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME);
  if (eye_tracking_social) out.emplace_back(XR_FB_EYE_TRACKING_SOCIAL_EXTENSION_NAME);
  return out;
}

GazeExtensions gaze_extensions_in(const std::vector<std::string>& offered) {
  auto has = [&offered](const char* n) { return std::find(offered.begin(), offered.end(), n) != offered.end(); };
  return {.eye_gaze_interaction = has(XR_EXT_EYE_GAZE_INTERACTION_EXTENSION_NAME),
          .eye_tracking_social = has(XR_FB_EYE_TRACKING_SOCIAL_EXTENSION_NAME)};
}

io::GazeRay gaze_ray(const XrPosef& pose, bool valid, std::optional<double> confidence) {
  const StagePose p = to_stage_pose(pose);
  io::GazeRay ray;
  ray.valid = valid;
  ray.confidence = confidence;
  ray.origin_m = p.position_m;
  ray.direction = glm::normalize(p.orientation * glm::dvec3(0.0, 0.0, -1.0));
  return ray;
}

io::Vergence vergence_of(const StagePose& head, const io::GazeRay& left, const io::GazeRay& right) {
  // Into the head's frame, where geometry's eyes and sight lines live
  // (x right, −z forward).
  const glm::dquat to_head = glm::conjugate(head.orientation);
  const geometry::EyeOffsets eyes{to_head * (left.origin_m - head.position_m),
                                  to_head * (right.origin_m - head.position_m)};
  const std::array<geometry::SightLine, 2> lines{
      geometry::SightLine{eyes.left_m, to_head * left.direction},
      geometry::SightLine{eyes.right_m, to_head * right.direction}};
  io::Vergence v;
  v.angle_rad = geometry::vergence_of(eyes, lines);
  const double ipd_m = glm::length(eyes.right_m - eyes.left_m);
  if (v.angle_rad > 0.0 && ipd_m > 0.0) v.distance_m = ipd_m / (2.0 * std::tan(0.5 * v.angle_rad));
  return v;
}

// What one session's eye tracking holds. The per-eye tracker is destroyed
// through the runtime's function, loaded with it.
struct EyeTracking::State {
  XrInstance instance = XR_NULL_HANDLE;
  std::optional<ActionSet> gaze_set;  // combined gaze
  XrSpace gaze_space = XR_NULL_HANDLE;
  bool per_eye = false;
  XrEyeTrackerFB tracker = XR_NULL_HANDLE;
  PFN_xrCreateEyeTrackerFB create_tracker = nullptr;
  PFN_xrDestroyEyeTrackerFB destroy_tracker = nullptr;
  PFN_xrGetEyeGazesFB get_gazes = nullptr;

  ~State() {
    if (tracker != XR_NULL_HANDLE && destroy_tracker != nullptr) (void)destroy_tracker(tracker);
    if (gaze_space != XR_NULL_HANDLE) (void)xrDestroySpace(gaze_space);
  }
};

EyeTracking::EyeTracking(std::unique_ptr<State> state) : state_(std::move(state)) {}
EyeTracking::EyeTracking(EyeTracking&&) noexcept = default;
EyeTracking& EyeTracking::operator=(EyeTracking&&) noexcept = default;
EyeTracking::~EyeTracking() = default;

bool EyeTracking::combined() const { return state_->gaze_set.has_value(); }
bool EyeTracking::per_eye() const { return state_->per_eye; }
XrActionSet EyeTracking::action_set() const {
  return state_->gaze_set ? state_->gaze_set->handle() : XR_NULL_HANDLE;
}

Result<EyeTracking> EyeTracking::create(const Instance& instance, XrSystemId system, GazeExtensions enabled) {
  auto state = std::make_unique<State>();
  state->instance = instance.handle();
  if (!enabled.any()) return EyeTracking(std::move(state));

  // XR_EXT_eye_gaze_interaction's system property says whether this headset
  // has combined gaze. XR_FB_eye_tracking_social's (supportsEyeTracking) is
  // not asked: an API layer older than the extension, such as Debian 12's
  // core validation layer (OpenXR 1.0.20), rejects its unknown structure in
  // the next chain of xrGetSystemProperties, failing the whole call. The
  // tracker's creation answers the same question instead: on a system
  // without eye tracking xrCreateEyeTrackerFB must fail with
  // XR_ERROR_FEATURE_UNSUPPORTED (the extension's specification), and
  // start() then runs the session without per-eye gaze.
  auto gaze_props = tagged<XrSystemEyeGazeInteractionPropertiesEXT>(XR_TYPE_SYSTEM_EYE_GAZE_INTERACTION_PROPERTIES_EXT);
  if (enabled.eye_gaze_interaction) {
    auto props = tagged<XrSystemProperties>(XR_TYPE_SYSTEM_PROPERTIES);
    props.next = &gaze_props;
    if (const XrResult r = xrGetSystemProperties(instance.handle(), system, &props); XR_FAILED(r))
      return failure_of(r, "xrGetSystemProperties");
  }

  if (enabled.eye_gaze_interaction && gaze_props.supportsEyeGazeInteraction == XR_TRUE) {
    auto set = ActionSet::create(instance, gaze_action_set());
    if (!set) return set.error();
    state->gaze_set.emplace(std::move(set).value());
  }
  if (enabled.eye_tracking_social) {
    const XrInstance xr = instance.handle();
    for (auto [name, r] : {std::pair{"xrCreateEyeTrackerFB", load(xr, "xrCreateEyeTrackerFB", state->create_tracker)},
                           std::pair{"xrDestroyEyeTrackerFB", load(xr, "xrDestroyEyeTrackerFB", state->destroy_tracker)},
                           std::pair{"xrGetEyeGazesFB", load(xr, "xrGetEyeGazesFB", state->get_gazes)}})
      if (XR_FAILED(r)) return failure_of(r, name);
    state->per_eye = true;
  }
  return EyeTracking(std::move(state));
}

Result<Done> EyeTracking::start(XrSession session) {
  State& s = *state_;
  if (s.gaze_set) {
    auto info = tagged<XrActionSpaceCreateInfo>(XR_TYPE_ACTION_SPACE_CREATE_INFO);
    info.action = s.gaze_set->action("gaze_pose");
    info.subactionPath = XR_NULL_PATH;
    info.poseInActionSpace = XrPosef{{0.0f, 0.0f, 0.0f, 1.0f}, {0.0f, 0.0f, 0.0f}};
    if (const XrResult r = xrCreateActionSpace(session, &info, &s.gaze_space); XR_FAILED(r))
      return failure_of(r, "xrCreateActionSpace");
  }
  if (s.per_eye) {
    auto info = tagged<XrEyeTrackerCreateInfoFB>(XR_TYPE_EYE_TRACKER_CREATE_INFO_FB);
    if (const XrResult r = s.create_tracker(session, &info, &s.tracker); XR_FAILED(r)) {
      // No eye tracker in this headset (XR_ERROR_FEATURE_UNSUPPORTED), or
      // refused (the participant did not grant the runtime's eye-tracking
      // permission): the session runs without per-eye gaze.
      if (fatal(r)) return failure_of(r, "xrCreateEyeTrackerFB");
      if (r != XR_ERROR_FEATURE_UNSUPPORTED)
        std::cerr << "curvlab: xr: per-eye gaze unavailable: " << failure_of(r, "xrCreateEyeTrackerFB").message
                  << '\n';
      s.tracker = XR_NULL_HANDLE;
      s.per_eye = false;
    }
  }
  return Done{};
}

EyeTracking::Located EyeTracking::locate(XrSpace stage, XrTime time, const StagePose& head) const {
  const State& s = *state_;
  Located out;
  if (s.gaze_space != XR_NULL_HANDLE) {
    // The sample's own time (XrEyeGazeSampleTimeEXT) is when the eyes were
    // seen; the pose is predicted to `time`, as every other pose of the frame.
    auto sample_time = tagged<XrEyeGazeSampleTimeEXT>(XR_TYPE_EYE_GAZE_SAMPLE_TIME_EXT);
    auto loc = tagged<XrSpaceLocation>(XR_TYPE_SPACE_LOCATION);
    loc.next = &sample_time;
    const XrResult r = xrLocateSpace(s.gaze_space, stage, time, &loc);
    if (fatal(r)) return {{}, r, "xrLocateSpace"};
    constexpr XrSpaceLocationFlags want =
        XR_SPACE_LOCATION_POSITION_VALID_BIT | XR_SPACE_LOCATION_ORIENTATION_VALID_BIT;
    out.gaze.combined = gaze_ray(loc.pose, XR_SUCCEEDED(r) && (loc.locationFlags & want) == want);
  }
  if (s.tracker != XR_NULL_HANDLE) {
    auto info = tagged<XrEyeGazesInfoFB>(XR_TYPE_EYE_GAZES_INFO_FB);
    info.baseSpace = stage;
    info.time = time;
    auto gazes = tagged<XrEyeGazesFB>(XR_TYPE_EYE_GAZES_FB);
    const XrResult r = s.get_gazes(s.tracker, &info, &gazes);
    if (fatal(r)) return {{}, r, "xrGetEyeGazesFB"};
    std::array<io::GazeRay, 2> eyes;
    for (std::size_t i = 0; i < 2; ++i)
      eyes[i] = gaze_ray(gazes.gaze[i].gazePose, XR_SUCCEEDED(r) && gazes.gaze[i].isValid == XR_TRUE,
                         XR_SUCCEEDED(r) ? std::optional<double>(std::clamp(gazes.gaze[i].gazeConfidence, 0.0f, 1.0f))
                                         : std::nullopt);
    if (eyes[0].valid && eyes[1].valid) out.gaze.vergence = vergence_of(head, eyes[0], eyes[1]);
    out.gaze.eyes = eyes;
  }
  return out;
}

}  // namespace curvlab::harness::xr
