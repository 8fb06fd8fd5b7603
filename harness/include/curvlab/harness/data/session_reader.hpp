// Reading a stored session back: what `curvlab resume` needs to continue a
// session and what `curvlab replay` needs to redraw one of its frames. With
// SessionStore (writing) and SampleWriter (samples and frames) these
// functions are the schema's only door: code outside data/ holds no SQL
// (STYLE.md, "SQL outside data/"). Each returns typed records; a SQLite
// failure becomes an Error naming the file, a missing session or trial an
// Error of kind not_found, a stored value that breaks its documented form
// (a pose blob of the wrong size, an onset event without its fields) an
// Error of kind corrupt — never a crash, never a silently wrong image.
//
// They read through any open Database (read_only for replay, open_existing
// or create_or_open for resume); like Database, one thread at a time.
#pragma once

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/records.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::data {

// The simulated observer's parameters as the session's `observer` event
// stored them (codebook: events.kind): its JSON, which the runner reads
// (runner/observer.hpp, observer_from_json).
struct StoredObserver {
  std::string json;
};

// Everything a session was started with, to start it again identically.
struct SessionProvenance {
  std::int64_t session_id = 0;
  std::string protocol_text;
  std::optional<std::string> protocol_source_path;  // where the protocol was read from, if known
  std::string pseudonym;
  DominantEye dominant_eye = DominantEye::unknown;
  std::optional<double> ipd_m;  // participants.ipd_m
  std::int64_t seed = 0;        // sessions.seed (the design's seed, stored as a signed 64-bit value)
  SessionStatus status = SessionStatus::running;
  std::optional<Backend> backend;  // nullopt: 'unknown' (migrated from version 1)
  std::optional<std::string> table_calibration_json;
  // From the session_start event; nullopt when the session has none (it
  // cannot be resumed: the design cannot be expanded again).
  std::optional<std::uint64_t> participant_number;
  std::optional<StoredObserver> observer;  // from the observer event, if any
  // Samples per pixel the session drew with (session_start); nullopt: not
  // recorded (sessions from before multisampling drew with 1), 0: nothing drawn.
  std::optional<std::uint32_t> msaa;
  // The run options it last ran with (session_start, or the latest resume
  // that recorded them; a JSON object's text); nullopt: none recorded.
  std::optional<std::string> run_options_json;
  // The latest time stamp logged for the session (frames and events), 0 if
  // none: a resumed session's clock must not run backwards past it.
  std::int64_t last_t_ns = 0;
};

// sessions ⋈ protocols ⋈ participants plus the session_start and observer
// events. not_found when there is no such session.
Expected<SessionProvenance> read_session_provenance(Database& db, std::int64_t session_id);

// One stored trial of the session's plan.
struct StoredTrial {
  std::int64_t trial_id = 0;
  std::int64_t trial_index = 0;
  std::string conditions_json;  // trials.conditions, as stored (compared verbatim on resume)
};
// The session's whole plan in trial_index order (empty when it has none).
Expected<std::vector<StoredTrial>> read_trial_list(Database& db, std::int64_t session_id);

// The largest frames.frame_index of the session, -1 when it has no frame: a
// resumed run numbers its frames from this plus one.
Expected<std::int64_t> read_last_frame_index(Database& db, std::int64_t session_id);

// A committed staircase step's outcome, in commit (step_id) order: replaying
// them through the staircases restores their state on resume.
struct StoredStaircaseResponse {
  std::int64_t trial_id = 0;
  std::optional<bool> response_correct;  // NULL: no answer counted
};
Expected<std::vector<StoredStaircaseResponse>> read_staircase_responses(Database& db,
                                                                        std::int64_t session_id);

// ---- replay ----------------------------------------------------------------

// trials.trial_id of (session, trial_index); not_found when absent.
Expected<std::int64_t> read_trial_id(Database& db, std::int64_t session_id, std::int64_t trial_index);

// The trial's latest `onset` event (its last attempt's): where the stimulus
// was placed and when it was first shown. nullopt: the trial never reached
// its onset. corrupt: the event lacks frame_index, head_pose or stick_pose.
struct OnsetRecord {
  std::int64_t event_id = 0;  // later events of the trial belong to this attempt
  std::int64_t frame_index = 0;
  std::int64_t predicted_display_ns = 0;
  std::int64_t attempt = 0;
  std::array<double, 16> head_pose{};   // column-major 4×4 isometry at onset
  std::array<double, 16> stick_pose{};  // column-major 4×4 isometry of the stick
};
Expected<std::optional<OnsetRecord>> read_onset(Database& db, std::int64_t trial_id);
// A play block's shots (table shots), in order.
Expected<std::vector<ShotRecord>> read_shots(Database& db, std::int64_t trial_id);

// staircase_steps.intensity of the trial (the value it showed), if it was a
// staircase trial whose step was committed.
Expected<std::optional<double>> read_staircase_intensity(Database& db, std::int64_t trial_id);

// The method-of-adjustment value in force at `frame_index` of the attempt
// whose onset event is `onset_event_id`: the last `adjustment` event of that
// attempt (events after the onset) logged at or before the frame. nullopt:
// no change yet (the trial's adjustment_start applies).
Expected<std::optional<double>> read_adjustment_at(Database& db, std::int64_t trial_id,
                                                   std::int64_t onset_event_id, std::int64_t frame_index);

// The head's logged virtual pose in one frame (tracking_samples, device
// 'head'). nullopt: no head sample with a virtual pose in that frame.
// corrupt: the blob is not 16 doubles (128 bytes).
struct HeadAtFrame {
  std::optional<std::int64_t> trial_id;  // the trial it was logged under, nullopt between trials
  std::int64_t t_ns = 0;                  // the frame's predicted display time
  std::array<double, 16> virtual_pose{};  // column-major 4×4 isometry
};
Expected<std::optional<HeadAtFrame>> read_head_at_frame(Database& db, std::int64_t session_id,
                                                        std::int64_t frame_index);

// The first and last frame with a head sample logged under the trial, for
// messages; nullopt when it has none.
struct FrameSpan {
  std::int64_t first = 0;
  std::int64_t last = 0;
};
Expected<std::optional<FrameSpan>> read_trial_frame_span(Database& db, std::int64_t trial_id);

// The eye geometry `frame_index` was drawn with: the latest frame at or
// before it that stored one (frames.eye_views NULL means "unchanged").
// nullopt: the session recorded none up to that frame (schema version 2, or
// a runner that did not fill FrameRecord::view_geometry). corrupt: a blob
// that is not 256 bytes.
// How many events of `kind` a trial logged (e.g. its trial_aborted events:
// the attempts that ended in an abort, which a resumed session's random
// streams count).
Expected<std::int64_t> read_trial_event_count(Database& db, std::int64_t trial_id, EventKind kind);

Expected<std::optional<ViewGeometry>> read_view_geometry(Database& db, std::int64_t session_id,
                                                         std::int64_t frame_index);

}  // namespace curvlab::harness::data
