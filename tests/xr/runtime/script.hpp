// What the test runtime's scripted headset does, read from the environment
// (variables documented at the top of runtime.cpp): where the head and hands
// are at a given time, which controller inputs are held, when focus is lost
// and regained, when the runtime asks the application to exit, and how it
// departs from an ideal headset as real runtimes do (display-time jitter,
// back-pressure, a slow bring-up, STAGE moves, lost events, format order,
// changing views, partial tracking, refresh rates). Pure
// functions of time, so the poses the runtime hands out can be logged and
// checked against what the application stored.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace curvlab::test_runtime {

struct Vec3 {
  double x = 0.0, y = 0.0, z = 0.0;
};

// Unit quaternion, OpenXR's order of members (x, y, z, w).
struct Quat {
  double x = 0.0, y = 0.0, z = 0.0, w = 1.0;
};

struct Pose {
  Quat orientation;
  Vec3 position_m;
};

Quat multiply(const Quat& a, const Quat& b);
Vec3 rotate(const Quat& q, const Vec3& v);
Quat conjugate(const Quat& q);
Pose compose(const Pose& a, const Pose& b);  // a ∘ b: b expressed in a's frame
Pose inverse(const Pose& p);

// One scripted controller press: `button` of `hand` goes down at `at_s`
// (seconds after the session first became FOCUSED), up `hold_s` later, and
// again every `every_s` (0: once).
struct Press {
  std::string hand;    // "left" or "right"
  std::string button;  // a b x y menu trigger squeeze
  double at_s = 0.0;
  double every_s = 0.0;
  double hold_s = 0.08;
};

// A scripted hand placement: from `at_s` (seconds after the session first
// became FOCUSED) on, until the same hand's next placement, the hand's grip
// is at `position_m` in STAGE, unrotated.
struct Placement {
  int hand = 1;  // 0 left, 1 right
  double at_s = 0.0;
  Vec3 position_m;
};

// A spell without input focus: FOCUSED → VISIBLE at `at_s`, back after `for_s`.
struct Unfocus {
  double at_s = 0.0;
  double for_s = 0.0;
};

// The runtime stops the session and starts it again: at `at_s` it steps
// down to STOPPING (through VISIBLE and SYNCHRONIZED); after the
// application's xrEndSession the session is IDLE for `idle_s`, then READY;
// once the application has begun it again and ended a frame, SYNCHRONIZED,
// VISIBLE and FOCUSED follow, as at the start.
struct Restart {
  double at_s = 0.0;
  double idle_s = 0.0;
};

// A runtime fault: from the first call of `call` at or after `at_s` on,
// that call returns `result` (a lost session stays lost).
struct Fault {
  std::string call;    // xrWaitFrame or xrEndFrame
  double at_s = 0.0;   // seconds after the session first became FOCUSED
  std::string result;  // XR_ERROR_SESSION_LOST, XR_ERROR_RUNTIME_FAILURE or XR_ERROR_INSTANCE_LOST
};

// CURVLAB_TEST_XR_TIMING: predicted display times as a compositor's are, a
// little early or late (uniform within ±jitter_ms of the display grid), and
// frames whose wake-up misses a refresh (probability `miss` per frame); the
// pattern is a pure function of (seed, frame number), so a test can repeat it.
struct Timing {
  double jitter_ms = 0.0;
  double miss = 0.0;
  std::uint64_t seed = 1;
};

// CURVLAB_TEST_XR_SWAPCHAIN_WAIT: the compositor still reads every `every`-th
// image acquired from a swapchain for `ms` after it is acquired, so
// xrWaitSwapchainImage waits (XR_TIMEOUT_EXPIRED when the application's
// timeout is shorter).
struct SwapchainStall {
  double ms = 0.0;
  int every = 0;  // 0: never
};

// CURVLAB_TEST_XR_STATES: the session comes up as real runtimes bring it:
// READY `ready_s` after xrCreateSession, SYNCHRONIZED after the first
// xrEndFrame, VISIBLE `visible_frames` frames later, FOCUSED
// `focused_frames` frames after that (the defaults: all at once).
struct BringUp {
  double ready_s = 0.0;
  int visible_frames = 0;
  int focused_frames = 0;
};

// CURVLAB_TEST_XR_STAGE_MOVE: at `at_s` (after focus) the runtime announces
// that STAGE moves (XrEventDataReferenceSpaceChangePending): from 0.1 s
// later on, STAGE's origin is `origin` (in the previous STAGE); the room,
// the table, the head and the hands stay where they are.
struct StageMove {
  double at_s = 0.0;
  Pose origin;
  bool pose_valid = true;  // false: the event says the runtime does not know the move
};

// CURVLAB_TEST_XR_VIEWS: views that differ from the plain headset: each eye
// turned outward by `cant_deg` about the head's vertical (canted displays),
// and, per frame, an IPD between ipd_min_m and ipd_max_m and fields of view
// scaled by up to ±fov_change, as pure functions of the display time.
struct Views {
  double cant_deg = 0.0;
  double ipd_min_m = 0.0;  // 0: the fixed kIpdM
  double ipd_max_m = 0.0;
  double fov_change = 0.0;
};

// CURVLAB_TEST_XR_TRACKING: a spell of partial tracking of one device.
enum class TrackingMode {
  inferred,          // position and orientation valid, neither tracked
  orientation_only,  // orientation valid and tracked, position not valid
  lost,              // nothing valid
};
struct TrackingSpell {
  int device = 0;  // 0 head, 1 left hand, 2 right hand
  TrackingMode mode = TrackingMode::inferred;
  double at_s = 0.0;  // after focus
  double for_s = 0.0;
};

// CURVLAB_TEST_XR_REFRESH and CURVLAB_TEST_XR_REFRESH_CHANGE
// (XR_FB_display_refresh_rate): the rates the display offers, the one it
// starts at, and a change the runtime makes itself (`change_at_s` after focus).
struct Refresh {
  std::vector<float> rates{90.0f};
  float start_hz = 90.0f;
  std::optional<double> change_at_s;
  float change_to_hz = 0.0f;
};

// Scripted eyes (CURVLAB_TEST_XR_GAZE; eyes.hpp reads it and places them).
struct GazeScript {
  bool combined = true;  // offer XR_EXT_eye_gaze_interaction
  bool per_eye = true;   // offer XR_FB_eye_tracking_social
  // Both eyes fixate this STAGE point; nullopt: they hold `vergence_deg`,
  // turned symmetrically about the head's forward direction in the plane of
  // the eyes' axis (positive converging, negative diverging).
  std::optional<Vec3> fixate_m;
  double vergence_deg = 0.0;
  std::array<double, 2> confidence{1.0, 1.0};  // left, right (per-eye gaze)
};

struct Script {
  std::vector<Press> presses;
  std::vector<Placement> placements;  // CURVLAB_TEST_XR_HAND, in time order per hand
  std::optional<Fault> fault;
  std::vector<Unfocus> unfocus;
  std::optional<double> exit_at_s;  // request exit (STOPPING) at this time
  std::optional<Restart> restart;   // STOPPING → IDLE → READY at this time
  std::optional<double> loss_at_s;  // LOSS_PENDING at this time; frame calls fail SESSION_LOST 0.5 s later
  // CURVLAB_TEST_XR_HEAD=orientation_only: the head's position is valid but
  // not tracked (inferred), its orientation tracked, as Monado's simulated
  // headset reports it.
  bool head_position_tracked = true;
  std::string capture_dir;          // left-eye PNGs of submitted frames
  int capture_every = 1;            // every n-th submitted frame
  std::string log_path;             // what the runtime handed out and saw
  std::uint32_t eye_width_px = 320;
  std::uint32_t eye_height_px = 320;
  // CURVLAB_TEST_XR_LATE: frames (numbered from 0 in xrWaitFrame order) whose
  // predicted display time skips one period (the runtime wakes the
  // application a refresh later), and frames with shouldRender false.
  std::set<std::int64_t> late_skip;
  std::set<std::int64_t> late_hidden;
  Timing timing;
  SwapchainStall swapchain_stall;
  BringUp bring_up;
  std::optional<StageMove> stage_move;
  std::optional<double> events_lost_at_s;  // CURVLAB_TEST_XR_EVENTS_LOST
  std::uint32_t events_lost = 0;
  // CURVLAB_TEST_XR_FORMATS: the swapchain formats offered (VkFormat
  // numbers), in the runtime's order of preference.
  std::vector<std::int64_t> formats;
  Views views;
  std::vector<TrackingSpell> tracking;
  Refresh refresh;
  // CURVLAB_TEST_XR_GAZE (eyes.hpp): nullopt offers no eye tracking.
  std::optional<GazeScript> gaze;
};

// A uniform number in [0, 1) from (seed, n, stream): the same triple gives
// the same number in every run.
double uniform(std::uint64_t seed, std::int64_t n, int stream);

// The scripted partial tracking of `device` (0 head, 1 left, 2 right)
// `since_focus_s` after focus; nullopt: tracked as usual.
std::optional<TrackingMode> tracking_mode(const Script& script, int device, double since_focus_s);

// One eye's view relative to the head at time t_s (seconds on the runtime's
// clock): pose in the head's frame and field of view (left, right, up,
// down, radians).
struct EyeView {
  Pose pose;
  double fov_rad[4] = {0.0, 0.0, 0.0, 0.0};
};
EyeView eye_view(const Script& script, int eye, double t_s);

// A whole string as a finite number, or nullopt.
std::optional<double> parse_number(const std::string& text);

// Reads the CURVLAB_TEST_XR_* variables; a malformed one is an error naming
// the variable and what was expected.
std::optional<Script> read_script(std::string& error);

// Head pose in STAGE space at time t_s (seconds on the runtime's clock): a
// person standing 0.35 m behind the near edge of a 1 m table centred at the
// origin, eyes 1.6 m up, looking 25° down, swaying slowly.
Pose head_pose(double t_s);
// Left (hand 0) or right (hand 1) grip pose: resting on the near edge.
Pose hand_pose(int hand, double t_s);
// The same, where the script places the hand: the latest placement of that
// hand at or before `since_focus_s` (seconds after the session first became
// FOCUSED), else the resting pose.
Pose hand_pose(const Script& script, int hand, double t_s, double since_focus_s);

// Interpupillary distance of the scripted headset.
inline constexpr double kIpdM = 0.064;

// Whether `press` holds its button down at time t_s, and if so since when.
std::optional<double> held_since(const Press& press, double t_s);
// The last time at or before t_s at which `press` changed its button (down
// or up); nullopt before its first press.
std::optional<double> last_change(const Press& press, double t_s);

}  // namespace curvlab::test_runtime
