// The session's events, one struct each (data_schema/codebook.md, "events"):
// the runner builds these, the data layer turns each into its `events` row
// (kind and JSON detail) and reads the ones it needs back. The kind names
// and JSON keys live only here and in events.cpp.
#pragma once

#include "curvlab/harness/data/error.hpp"
#include "curvlab/harness/data/records.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::harness::data {

enum class EventKind {
  session_start,
  observer,
  resume,
  block_start,
  instructions,  // an instruction page shown
  break_page,    // a break page shown (stored as "break")
  done,          // the closing page shown
  session_end,
  signal,
  operator_action,
  operator_note,
  paused,
  unpaused,
  trial_aborted,
  trial_repeated,
  trial_abandoned,
  trial_skipped,
  early_input,
  adjustment,
  onset,
  tracking_flagged,
  events_lost,   // the headset's runtime dropped events
  stage_moved,   // the headset's STAGE origin moved
  refresh_rate,  // the headset's refresh rate changed
  posterior,  // a Bayesian adaptive method's posterior after the trial's answer
  play_summary,  // a play block's figures when it ends (docs/billiards.md)
  strike,        // a play block's strike of the cue ball
  pocket,        // a ball pocketed in a play block
  questionnaire_start,  // a questionnaire block's first item (or a resumed run's) is shown
  questionnaire_end,    // a questionnaire block's last item was answered
  merged_from,
  session_renumbered,
  feedback,      // what the participant was shown after an answer (judgement.feedback)
  shared_game,     // a shared play block's game and partner (docs/shared_play.md)
  partner_clock,   // the partner's clock offset, measured every few seconds
  shared_shot,     // who shot, and how the other station's simulation compared
  shared_network,  // the link's figures when a shared play block ends
  partner_left,    // the partner disconnected; the game pauses
  partner_back,    // the partner came back; the game goes on
};

std::string_view to_string(EventKind kind);
std::optional<EventKind> parse_event_kind(std::string_view text);

using Pose16 = std::array<double, 16>;  // column-major 4×4

namespace events {

struct SessionStart {
  std::uint64_t participant_number = 1;
  std::uint64_t seed = 0;
  std::uint64_t protocol_seed = 0;
  std::string backend;
  std::uint32_t msaa = 1;
  std::size_t trials = 0;
  std::optional<std::size_t> counterbalance_row;
  // The command line's run options (a JSON object: render, pace, images,
  // export, observer), the defaults of `resume`; nullopt: not recorded.
  std::optional<std::string> run_options_json;
  // What the protocol was warned about when the session started (the human
  // model's range of validity; runner/stimulus_checks.hpp), for the report.
  std::vector<std::string> warnings;
};
// The simulated observer's parameters, as the runner writes them.
struct Observer {
  std::string params_json;
};
struct Resume {
  std::size_t from_trial = 0;
  std::string backend;
  std::optional<std::string> run_options_json;  // as SessionStart's: those the continuation ran with
};
struct BlockStart {
  std::string block;
  std::int64_t block_index = 0;
};
// A page of text: `kind` is instructions, break_page or done.
struct Page {
  EventKind kind = EventKind::instructions;
  std::size_t page = 0;
  std::string text;
};
struct SessionEnd {
  SessionStatus status = SessionStatus::completed;
};
struct Signal {
  int signal = 0;
};
struct OperatorActionEvent {
  std::string action;
  std::string source;
  std::int64_t t_ns = 0;
  std::optional<std::string> text;  // a note's text (an operator_note event)
};
struct Paused {
  std::string phase;
};
struct Unpaused {
  std::string phase;
  double paused_ms = 0.0;
};
struct TrialAborted {
  std::string reason;
  std::int64_t attempt = 0;
};
struct TrialRepeated {
  std::string reason;
};
struct TrialAbandoned {
  std::string reason;
  std::int64_t attempts = 0;
};
struct TrialSkipped {
  std::string reason;
  std::int64_t attempts = 0;
};
struct EarlyInput {
  std::string name;
  std::string device;
  std::int64_t t_ns = 0;
};
struct AdjustmentEvent {
  double value = 0.0;
  std::int64_t frame_index = 0;
};
struct Onset {
  std::int64_t frame_index = 0;
  std::int64_t predicted_display_ns = 0;
  std::int64_t attempt = 1;
  Pose16 head_pose{};
  Pose16 stick_pose{};
  int views = 0;
  int draws = 0;
  std::optional<double> perceived_sagitta_m;
  // The human observer's account of its percept (a JSON object: fused,
  // signal_arcsec, threshold_arcsec, d_prime, perceived_distance_m, …).
  std::optional<std::string> percept_json;
  std::optional<std::vector<std::string>> images;
  // How long the stimulus phase lasts from this onset (timeline.stimulus_ms):
  // the window the exports summarise gaze over.
  std::optional<std::int64_t> stimulus_ms;
};
struct TrackingFlagged {
  double lost_ms = 0.0;
  std::int64_t spells = 0;
  std::int64_t attempt = 0;
};
struct EventsLost {
  std::uint32_t lost_events = 0;
};
struct StageMoved {
  std::int64_t change_ns = 0;
  bool pose_valid = false;
  std::array<double, 7> origin{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0};  // x y z (m), qx qy qz qw
  bool kept_lab_frame = false;
};
struct RefreshRate {
  double from_hz = 0.0;
  double to_hz = 0.0;
  bool requested = false;
};
// Written by the store with the step it follows (SessionStore::complete_trial).
struct Posterior {
  std::string staircase;  // the step's staircase_steps.staircase
  std::int64_t step_index = 0;
  StepPosterior value;
};

// A play block's figures: shots, balls pocketed, time, distance walked,
// laps round the physical and the virtual table (from the head's unwrapped
// azimuth about each table's centre), and the seen-versus-felt hand error.
struct PlaySummary {
  std::string block;
  // Why the game ended: time, shots, all_pocketed, no_balls; in a shared
  // game also partner_ended (the partner's station ended it) or partner_lost
  // (the partner was away longer than --partner-wait-s).
  std::string ended;
  std::int64_t shots = 0;
  std::int64_t pocketed = 0;
  double time_s = 0.0;
  double walked_m = 0.0;
  double laps_physical = 0.0;
  double laps_virtual = 0.0;
  double hand_error_m = 0.0;  // mean over frames, both hands
};

// A strike in a play block, at the display time of its frame.
struct Strike {
  std::int64_t shot_index = 0;
  std::string ball;
  double speed_m_s = 0.0;
  bool miscue = false;
};
// A ball pocketed by a shot, at the moment it fell (the strike's time plus
// the event's simulated time).
struct Pocket {
  std::int64_t shot_index = 0;
  std::string ball;
  std::int64_t pocket = 0;
};

// A questionnaire block starts (docs/questionnaires.md): its instrument,
// how many items it has and the first this run shows (0, or where a resumed
// run goes on).
struct QuestionnaireStart {
  std::string block;
  std::string instrument;
  std::int64_t items = 0;
  std::int64_t first_item = 0;
};
// A questionnaire block's last item answered: the answers its trial holds.
struct QuestionnaireEnd {
  std::string block;
  std::string instrument;
  std::int64_t answered = 0;
};
// Shared play (docs/shared_play.md, "Data").
struct SharedGame {
  std::string game_uuid;
  std::string role;  // this station's: host or join
  std::string partner_initials;
  std::string partner_version;
  std::int64_t completed_shots = 0;  // when this station (re)joined
};
// partner clock − this session's clock = offset_ns, within ± uncertainty_ns.
struct PartnerClock {
  std::int64_t offset_ns = 0;
  std::int64_t round_trip_ns = 0;
  std::int64_t uncertainty_ns = 0;
  std::int64_t samples = 0;
};
struct SharedShot {
  std::int64_t shot_index = 0;
  std::string shooter;  // host or join
  bool local = false;   // this station shot it
  // The partner's shot simulated again here from its inputs: whether every
  // event and the rest state agreed, and the largest distance between a
  // ball's rest places (the sender's are kept).
  bool same_events = true;
  double rest_difference_m = 0.0;
};
struct SharedNetwork {
  double rtt_ms = 0.0;  // ENet's mean round trip of reliable packets
  double loss = 0.0;    // ENet's mean reliable-packet loss, 0–1
  std::int64_t poses_received = 0, poses_late = 0, poses_lost = 0;
  std::int64_t bytes_sent = 0, bytes_received = 0;
  std::int64_t dropped = 0;  // malformed or oversized messages
  std::int64_t disconnects = 0;
};
struct PartnerLeft {
  std::int64_t completed_shots = 0;
};
struct PartnerBack {
  std::int64_t completed_shots = 0;
  double away_s = 0.0;
};

}  // namespace events

using Event = std::variant<events::SessionStart, events::Observer, events::Resume, events::BlockStart, events::Page,
                           events::SessionEnd, events::Signal, events::OperatorActionEvent, events::Paused,
                           events::Unpaused, events::TrialAborted, events::TrialRepeated, events::TrialAbandoned,
                           events::TrialSkipped, events::EarlyInput, events::AdjustmentEvent, events::Onset,
                           events::TrackingFlagged, events::EventsLost, events::StageMoved, events::RefreshRate,
                           events::Posterior, events::PlaySummary, events::Strike, events::Pocket,
                           events::QuestionnaireStart, events::QuestionnaireEnd,
                           events::SharedGame, events::PartnerClock, events::SharedShot, events::SharedNetwork,
                           events::PartnerLeft, events::PartnerBack>;

// The row an event is stored as.
EventRecord event_record(std::int64_t session_id, std::optional<std::int64_t> trial_id, std::int64_t t_ns,
                         const Event& event);

// Reading back the details a resumed or replayed session needs; bad_input
// (the caller names the file) when the stored JSON lacks a field or has the
// wrong shape.
Expected<events::SessionStart> parse_session_start(const std::string& detail_json);
Expected<events::Onset> parse_onset(const std::string& detail_json);
// The run options of a session_start or resume event's detail (a JSON
// object's text), nullopt when it records none.
std::optional<std::string> parse_run_options(const std::string& detail_json);

}  // namespace curvlab::harness::data
