// Plain records the harness hands to the data layer; each maps to one table
// of data_schema/schema.sql (see data_schema/codebook.md for units).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::data {

enum class DominantEye { left, right, unknown };
enum class Backend { headless, desktop, xr };
enum class SessionStatus { running, paused, completed, aborted, interrupted };
enum class TrackedDevice : std::uint8_t { head, left_hand, right_hand, other };

const char* to_string(DominantEye eye);
const char* to_string(Backend backend);
const char* to_string(SessionStatus status);
const char* to_string(TrackedDevice device);

// No names or other identifying data: a pseudonym of [A-Za-z0-9_-], 1–32 chars.
bool valid_pseudonym(const std::string& pseudonym);
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

struct PlannedTrial {
  std::int64_t trial_id = 0;
  std::int64_t block_id = 0;
  std::int64_t block_index = 0;
  std::int64_t trial_index = 0;
  std::int64_t trial_in_block = 0;
  std::int64_t attempt = 0;  // attempts made so far (0: never started)
  std::string conditions_json;
  std::string stimulus_json;
};

struct StaircaseStep {
  std::string staircase;
  std::int64_t step_index = 0;
  double intensity = 0.0;
  std::optional<bool> response_correct;
  bool is_reversal = false;
  std::optional<double> next_intensity;
};

struct TrialResult {
  std::int64_t trial_id = 0;
  std::int64_t onset_ns = 0;     // predicted display time of the stimulus's first frame
  std::int64_t response_ns = 0;  // time stamp of the response event
  std::string response;
  std::string response_device;
  std::optional<StaircaseStep> staircase_step;  // committed in the same transaction
};

struct EventRecord {
  std::int64_t session_id = 0;
  std::optional<std::int64_t> trial_id;
  std::int64_t t_ns = 0;
  std::string kind;
  std::string detail_json = "{}";
};

// Body-coherent tracking state of one device (DESIGN.md §3).
struct TrackingState {
  std::int32_t physical_edge = -1;
  std::int32_t virtual_edge = -1;
  double laps = 0.0;
  double anchor_fraction = 0.0;
  double coherence_error_m = 0.0;
  double coherence_error_rad = 0.0;
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
  TrackingState state{};
};

struct FrameRecord {
  std::int64_t session_id = 0;
  std::int64_t trial_id = -1;  // -1: between trials (stored as NULL)
  std::int64_t frame_index = 0;
  std::int64_t t_ns = 0;
  std::int64_t predicted_display_ns = -1;  // -1: unknown (NULL)
  std::int64_t cpu_time_ns = 0;
  std::int64_t gpu_time_ns = -1;  // -1: unknown (NULL)
  std::int32_t dropped_frames = 0;
  std::int32_t views = 0;
  std::int32_t passes = 0;
  std::int32_t draws = 0;
  std::int64_t triangles = 0;
};

}  // namespace curvlab::data
