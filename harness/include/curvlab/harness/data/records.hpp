// Plain records the harness hands to the data layer; each maps to one table
// of data_schema/schema.sql (see data_schema/codebook.md for units).
#pragma once

#include "curvlab/harness/data/error.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::data {

enum class DominantEye { left, right, unknown };
enum class Backend { headless, desktop, xr };
enum class SessionStatus { running, paused, completed, aborted, interrupted };
enum class TrialStatus { pending, running, completed, skipped, aborted };
enum class TrackedDevice : std::uint8_t { head, left_hand, right_hand, other };

const char* to_string(DominantEye eye);
const char* to_string(Backend backend);
const char* to_string(SessionStatus status);
const char* to_string(TrialStatus status);
std::optional<Backend> parse_backend(std::string_view text);
std::optional<SessionStatus> parse_session_status(std::string_view text);
std::optional<TrialStatus> parse_trial_status(std::string_view text);
const char* to_string(TrackedDevice device);

// No names or other identifying data (docs/data.md, "Privacy"): 1–32
// characters of A-Z a-z 0-9 - _, not beginning with '-' (it would read as an
// option), no '@' (an e-mail address) and no date: a four-digit year
// 1900–2099 with a month (1–12) and a day (1–31), as year-month-day,
// day-month-year or month-day-year with one of - _ . / or a space between
// the numbers, or as eight digits in a row (YYYYMMDD, DDMMYYYY, MMDDYYYY).
// The error (bad_input) quotes the pseudonym and says which rule it breaks.
Expected<Done> check_pseudonym(const std::string& pseudonym);
bool valid_pseudonym(const std::string& pseudonym);  // check_pseudonym succeeds
struct ParticipantRecord {
  std::string pseudonym;
  std::optional<double> ipd_m;
  DominantEye dominant_eye = DominantEye::unknown;
};

struct SessionRecord {
  std::int64_t protocol_id = 0;
  std::int64_t participant_id = 0;
  std::optional<std::int64_t> session_number;  // default: the participant's next
  std::string software_version;
  std::string software_commit;
  Backend backend = Backend::headless;
  std::string renderer_device;
  std::string renderer_driver;
  std::optional<double> display_refresh_hz;
  std::int64_t seed = 0;
  std::optional<std::string> table_calibration_json;
  // The session's identity across files (uuid.hpp); empty: a new v7 UUID.
  std::string session_uuid;
};

// The design as expanded at session start: stored in full so a crash resumes
// exactly (DESIGN.md §6).
struct TrialPlan {
  std::string conditions_json = "{}";  // condition values, object of name → value
  std::string stimulus_json = "{}";    // stimulus parameters, object of name → value
};
struct BlockPlan {
  std::string name;
  bool is_practice = false;
  std::string settings_json = "{}";
  std::vector<TrialPlan> trials;
};

struct PlannedTrialRecord {
  std::int64_t trial_id = 0;
  std::int64_t block_id = 0;
  std::int64_t block_index = 0;
  std::int64_t trial_index = 0;
  std::int64_t trial_in_block = 0;
  std::int64_t attempt = 0;  // attempts made so far (0: never started)
  std::string conditions_json;
  std::string stimulus_json;
};

// A Bayesian adaptive method's posterior after a step (the psi method:
// protocol::PosteriorSummary): the marginal means and SDs of the PSE α (the
// parameter's unit), the slope β (per parameter unit) and, when estimated,
// the lapse rate λ, and the joint posterior's entropy in nats. Stored as the
// trial's `posterior` event, in the step's transaction.
struct StepPosterior {
  double pse_mean = 0.0, pse_sd = 0.0;
  double slope_mean = 0.0, slope_sd = 0.0;
  std::optional<double> lapse_mean, lapse_sd;
  double entropy_nats = 0.0;
};

struct StaircaseStep {
  std::string staircase;
  std::int64_t step_index = 0;
  double intensity = 0.0;
  std::optional<bool> response_correct;
  bool is_reversal = false;
  std::optional<double> next_intensity;
  std::optional<StepPosterior> posterior = std::nullopt;  // Bayesian methods (psi); nullopt for staircases
};

// One billiards shot of a play block (table shots; docs/billiards.md). The
// JSON columns hold what `curvlab billiards shot` reads and prints.
struct ShotRecord {
  std::int64_t session_id = 0;
  std::int64_t trial_id = 0;
  std::int64_t shot_index = 0;
  std::int64_t t_ns = 0;
  std::int64_t rest_ns = 0;
  std::string player;  // participant | simulated
  std::string ball;
  double aim_x = 0.0;
  double aim_z = 0.0;
  double speed_m_s = 0.0;
  std::optional<double> cue_speed_m_s;
  std::optional<double> tip_side;
  std::optional<double> tip_height;
  bool miscue = false;
  std::optional<std::string> cue_pose;
  std::string table_settings = "{}";
  std::string before_state = "{}";
  std::string shot = "{}";
  std::string events = "[]";
  std::string rest_state = "[]";
  std::string pocketed = "[]";
  std::int64_t event_count = 0;
};

// One item answered in a questionnaire block (table questionnaire_answers;
// docs/questionnaires.md): the item as it was shown, the scale point chosen
// and when. A questionnaire block is stored as one trial; its answers hang
// from that trial.
struct QuestionnaireAnswer {
  std::int64_t session_id = 0;
  std::int64_t trial_id = 0;
  std::string instrument;
  std::int64_t item_index = 0;  // 0-based, in the instrument's order
  std::string item_id;
  std::string item_text;
  std::int64_t value = 0;  // the scale point's value as answered (before any reversal)
  std::string label;       // the scale point's label
  std::int64_t shown_ns = 0;  // the item's first frame (session clock)
  std::int64_t t_ns = 0;      // the answering input (session clock)
  std::string device;         // io::to_string of the input's source
};

// One subscale of a questionnaire block, scored when the block ends (table
// questionnaire_scores): weight × (sum or mean of its items' scored values).
struct QuestionnaireScore {
  std::int64_t session_id = 0;
  std::int64_t trial_id = 0;
  std::string instrument;
  std::int64_t subscale_index = 0;
  std::string subscale;
  std::string rule;  // sum | mean
  double weight = 1.0;
  std::int64_t items = 0;     // items the subscale counts (an item counted twice, twice)
  std::int64_t answered = 0;  // of which answered
  std::optional<double> raw;    // sum or mean; nullopt unless every item was answered
  std::optional<double> score;  // weight × raw
};

struct TrialResult {
  std::int64_t trial_id = 0;
  std::int64_t onset_ns = 0;     // predicted display time of the stimulus's first frame
  std::int64_t response_ns = 0;  // time stamp of the response event
  std::string response;
  std::string response_device;
  std::optional<StaircaseStep> staircase_step;  // committed in the same transaction
  // The stimulus as shown, replacing the planned trials.stimulus (a
  // staircase's or an adjustment's value filled in); nullopt: as planned.
  std::optional<std::string> stimulus_json;
};

struct EventRecord {
  std::int64_t session_id = 0;
  std::optional<std::int64_t> trial_id;
  std::int64_t t_ns = 0;
  std::string kind;
  std::string detail_json = "{}";
};

// Body-coherent tracking state of one device (DESIGN.md §3).
struct TrackingStateRecord {
  std::int32_t physical_edge = -1;
  std::int32_t virtual_edge = -1;
  double laps = 0.0;
  double anchor_fraction = 0.0;
  double coherence_error_m = 0.0;
  double coherence_error_rad = 0.0;
  bool coherence_measured = true;  // false: both coherence errors stored as NULL
};

// One device at one instant. Trivially copyable so the ring buffer can hold it.
struct TrackingSample {
  std::int64_t session_id = 0;
  std::int64_t trial_id = -1;  // -1: between trials (stored as NULL)
  std::int64_t frame_index = 0;
  std::int64_t t_ns = 0;
  TrackedDevice device = TrackedDevice::head;
  bool position_valid = false;
  bool orientation_valid = false;
  bool has_virtual_pose = false;
  bool has_state = false;
  std::array<double, 3> lab_position_m{};
  std::array<double, 4> lab_orientation_xyzw{0.0, 0.0, 0.0, 1.0};
  std::array<double, 16> virtual_pose{};  // column-major 4x4 isometry
  TrackingStateRecord state{};
  // A shared game's partner as this station drew it (partner_samples, not
  // tracking_samples): `device` head, left_hand, right_hand or other (the
  // cue); position_valid: the partner's station tracked it; the pose in
  // virtual_pose. Lab columns are unused.
  bool partner = false;
  bool extrapolated = false;
  std::int64_t sample_age_ns = 0;
  double distance_m = -1.0;  // head: the players' geodesic distance; negative: none
};

// One gaze ray in the lab (STAGE) frame: where it starts (metres) and its
// unit direction. Lost tracking is data: `valid` false keeps the row.
struct GazeRayRecord {
  bool valid = false;
  double confidence = -1.0;  // 0–1 as the runtime reports it; negative: none reported
  std::array<double, 3> origin_m{};
  std::array<double, 3> direction{0.0, 0.0, -1.0};
};

// The participant's gaze at one frame's predicted display time (gaze_samples):
// the combined gaze ray (XR_EXT_eye_gaze_interaction) and each eye's
// (XR_FB_eye_tracking_social), where the headset tracks them, and the
// vergence of the two eyes. Trivially copyable so the ring buffer can hold it.
struct GazeSample {
  std::int64_t session_id = 0;
  std::int64_t trial_id = -1;  // -1: between trials (stored as NULL)
  std::int64_t frame_index = 0;
  std::int64_t t_ns = 0;
  bool has_combined = false;  // false: no combined gaze tracked (columns NULL)
  GazeRayRecord combined{};
  bool has_eyes = false;  // false: no per-eye gaze tracked (columns NULL)
  std::array<GazeRayRecord, 2> eyes{};  // left, right
  // Signed (positive converging, negative diverging beyond parallel); only
  // with both eyes valid.
  bool has_vergence = false;
  double vergence_rad = 0.0;
  double vergence_distance_m = -1.0;  // where the eyes' lines meet; <= 0: they do not (NULL)
};

// One eye as the renderer placed it, relative to the head (nose) pose in lab
// metres: OpenXR's view pose minus the head pose, or ±IPD/2 along the head's
// x axis (DESIGN.md §4, "Eye model"). Plain arrays so the record stays
// trivially copyable and free of renderer types.
struct EyeView {
  std::array<double, 3> position_m{};  // in the head's frame
  std::array<double, 9> rotation{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};  // column-major 3×3
  // Field of view as XrFovf: angle_left, angle_right, angle_up, angle_down
  // in radians from the view axis, left and down negative.
  std::array<double, 4> fov_rad{};
  bool operator==(const EyeView&) const = default;
};

// The eye geometry a frame was drawn with: what the backend reported (the
// OpenXR views of that frame, the desktop window's eye size and field of
// view, the headless target's) — everything replay needs to put the same
// pixels in the same places.
struct ViewGeometry {
  std::uint32_t width_px = 0;  // each eye's image
  std::uint32_t height_px = 0;
  std::array<EyeView, 2> eyes{};  // left, right
  bool operator==(const ViewGeometry&) const = default;
};

// frames.eye_views: per eye (left, then right) 16 doubles — position_m[3],
// rotation[9], fov_rad[4] — little-endian IEEE doubles like
// tracking_samples.virtual_pose: 256 bytes.
inline constexpr std::size_t eye_views_doubles = 32;
inline void encode_eye_views(const ViewGeometry& g, std::array<double, eye_views_doubles>& out) {
  std::size_t k = 0;
  for (const auto& e : g.eyes) {
    for (double v : e.position_m) out[k++] = v;
    for (double v : e.rotation) out[k++] = v;
    for (double v : e.fov_rad) out[k++] = v;
  }
}
inline void decode_eye_views(const std::array<double, eye_views_doubles>& in, ViewGeometry& g) {
  std::size_t k = 0;
  for (auto& e : g.eyes) {
    for (double& v : e.position_m) v = in[k++];
    for (double& v : e.rotation) v = in[k++];
    for (double& v : e.fov_rad) v = in[k++];
  }
}

struct FrameRecord {
  std::int64_t session_id = 0;
  std::int64_t trial_id = -1;  // -1: between trials (stored as NULL)
  std::int64_t frame_index = 0;
  std::int64_t t_ns = 0;
  std::int64_t predicted_display_ns = -1;  // -1: unknown (NULL)
  std::int64_t cpu_time_ns = 0;
  std::int64_t gpu_time_ns = -1;  // -1: unknown (NULL)
  std::int32_t dropped_frames = 0;
  std::int64_t display_period_ns = -1;  // -1: unknown (NULL)
  bool late = false;  // missed its display time, or the runtime said not to render
  std::int32_t views = 0;
  std::int32_t passes = 0;
  std::int32_t draws = 0;
  std::int64_t triangles = 0;
  // The eye geometry this frame was drawn with; false: not known (stored as
  // NULL, replay then assumes the protocol's IPD and a 90° field of view).
  // The writer stores it only when it differs from the last frame it wrote
  // for the session (frames.eye_views NULL means "unchanged"), so filling it
  // on every frame costs a comparison, not a row's worth of bytes.
  bool has_view_geometry = false;
  ViewGeometry view_geometry{};
};

}  // namespace curvlab::harness::data
