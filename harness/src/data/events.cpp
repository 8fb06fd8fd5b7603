#include "curvlab/harness/data/events.hpp"

#include <nlohmann/json.hpp>

#include <array>

namespace curvlab::harness::data {
namespace {

// Key order is kept as written (ordered_json): the stored detail reads in
// the order a person expects, and equal events give equal texts.
using Json = nlohmann::ordered_json;

constexpr std::array<std::pair<EventKind, std::string_view>, 39> kind_names{{
    {EventKind::session_start, "session_start"},
    {EventKind::observer, "observer"},
    {EventKind::resume, "resume"},
    {EventKind::block_start, "block_start"},
    {EventKind::instructions, "instructions"},
    {EventKind::break_page, "break"},
    {EventKind::done, "done"},
    {EventKind::session_end, "session_end"},
    {EventKind::signal, "signal"},
    {EventKind::operator_action, "operator_action"},
    {EventKind::operator_note, "operator_note"},
    {EventKind::paused, "paused"},
    {EventKind::unpaused, "unpaused"},
    {EventKind::trial_aborted, "trial_aborted"},
    {EventKind::trial_repeated, "trial_repeated"},
    {EventKind::trial_abandoned, "trial_abandoned"},
    {EventKind::trial_skipped, "trial_skipped"},
    {EventKind::early_input, "early_input"},
    {EventKind::adjustment, "adjustment"},
    {EventKind::onset, "onset"},
    {EventKind::tracking_flagged, "tracking_flagged"},
    {EventKind::events_lost, "events_lost"},
    {EventKind::stage_moved, "stage_moved"},
    {EventKind::refresh_rate, "refresh_rate"},
    {EventKind::posterior, "posterior"},
    {EventKind::play_summary, "play_summary"},
    {EventKind::feedback, "feedback"},
    {EventKind::strike, "strike"},
    {EventKind::pocket, "pocket"},
    {EventKind::questionnaire_start, "questionnaire_start"},
    {EventKind::questionnaire_end, "questionnaire_end"},
    {EventKind::merged_from, "merged_from"},
    {EventKind::session_renumbered, "session_renumbered"},
    {EventKind::shared_game, "shared_game"},
    {EventKind::partner_clock, "partner_clock"},
    {EventKind::shared_shot, "shared_shot"},
    {EventKind::shared_network, "shared_network"},
    {EventKind::partner_left, "partner_left"},
    {EventKind::partner_back, "partner_back"},
}};

Json pose_json(const Pose16& m) {
  Json a = Json::array();
  for (const double v : m) a.push_back(v);
  return a;
}

bool read_pose(const Json& j, Pose16& out) {
  if (!j.is_array() || j.size() != 16) return false;
  for (std::size_t i = 0; i < 16; ++i) {
    if (!j[i].is_number()) return false;
    out[i] = j[i].get<double>();
  }
  return true;
}

// The kind and detail (a JSON text) of each event.
struct Detail {
  Detail(EventKind k, const Json& j) : kind(k), text(j.dump()) {}
  Detail(EventKind k, std::string t) : kind(k), text(std::move(t)) {}
  EventKind kind;
  std::string text;
};

Detail detail(const events::SessionStart& e) {
  Json j{{"participant_number", e.participant_number}, {"seed", e.seed}, {"protocol_seed", e.protocol_seed},
         {"backend", e.backend},  {"msaa", e.msaa},    {"trials", e.trials}};
  if (e.counterbalance_row) j["counterbalance_row"] = *e.counterbalance_row;
  if (e.run_options_json) j["run_options"] = Json::parse(*e.run_options_json, nullptr, false);
  if (!e.warnings.empty()) j["warnings"] = e.warnings;
  return {EventKind::session_start, j};
}
Detail detail(const events::Observer& e) { return {EventKind::observer, e.params_json}; }
Detail detail(const events::Resume& e) {
  Json j{{"from_trial", e.from_trial}, {"backend", e.backend}};
  if (e.run_options_json) j["run_options"] = Json::parse(*e.run_options_json, nullptr, false);
  return {EventKind::resume, j};
}
Detail detail(const events::BlockStart& e) {
  return {EventKind::block_start, Json{{"block", e.block}, {"block_index", e.block_index}}};
}
Detail detail(const events::Page& e) { return {e.kind, Json{{"page", e.page}, {"text", e.text}}}; }
Detail detail(const events::SessionEnd& e) { return {EventKind::session_end, Json{{"status", to_string(e.status)}}}; }
Detail detail(const events::Signal& e) { return {EventKind::signal, Json{{"signal", e.signal}}}; }
Detail detail(const events::OperatorActionEvent& e) {
  Json j{{"action", e.action}, {"source", e.source}, {"t_ns", e.t_ns}};
  if (e.text) j["text"] = *e.text;
  return {e.text ? EventKind::operator_note : EventKind::operator_action, j};
}
Detail detail(const events::Paused& e) { return {EventKind::paused, Json{{"phase", e.phase}}}; }
Detail detail(const events::Unpaused& e) {
  return {EventKind::unpaused, Json{{"phase", e.phase}, {"paused_ms", e.paused_ms}}};
}
Detail detail(const events::TrialAborted& e) {
  return {EventKind::trial_aborted, Json{{"reason", e.reason}, {"attempt", e.attempt}}};
}
Detail detail(const events::TrialRepeated& e) { return {EventKind::trial_repeated, Json{{"reason", e.reason}}}; }
Detail detail(const events::TrialAbandoned& e) {
  return {EventKind::trial_abandoned, Json{{"reason", e.reason}, {"attempts", e.attempts}}};
}
Detail detail(const events::TrialSkipped& e) {
  return {EventKind::trial_skipped, Json{{"reason", e.reason}, {"attempts", e.attempts}}};
}
Detail detail(const events::EarlyInput& e) {
  return {EventKind::early_input, Json{{"name", e.name}, {"device", e.device}, {"t_ns", e.t_ns}}};
}
Detail detail(const events::AdjustmentEvent& e) {
  return {EventKind::adjustment, Json{{"value", e.value}, {"frame_index", e.frame_index}}};
}
Detail detail(const events::Onset& e) {
  Json j{{"frame_index", e.frame_index},
         {"predicted_display_ns", e.predicted_display_ns},
         {"attempt", e.attempt},
         {"head_pose", pose_json(e.head_pose)},
         {"stick_pose", pose_json(e.stick_pose)},
         {"views", e.views},
         {"draws", e.draws}};
  if (e.perceived_sagitta_m) j["perceived_sagitta_m"] = *e.perceived_sagitta_m;
  if (e.percept_json) j["percept"] = Json::parse(*e.percept_json);
  if (e.images) j["images"] = *e.images;
  if (e.stimulus_ms) j["stimulus_ms"] = *e.stimulus_ms;
  return {EventKind::onset, j};
}
Detail detail(const events::TrackingFlagged& e) {
  return {EventKind::tracking_flagged, Json{{"lost_ms", e.lost_ms}, {"spells", e.spells}, {"attempt", e.attempt}}};
}

Detail detail(const events::EventsLost& e) { return {EventKind::events_lost, Json{{"lost_events", e.lost_events}}}; }
Detail detail(const events::StageMoved& e) {
  Json origin = Json::array();
  for (const double v : e.origin) origin.push_back(v);
  return {EventKind::stage_moved, Json{{"change_ns", e.change_ns},
                                       {"pose_valid", e.pose_valid},
                                       {"origin", e.pose_valid ? origin : Json(nullptr)},
                                       {"kept_lab_frame", e.kept_lab_frame}}};
}
Detail detail(const events::RefreshRate& e) {
  return {EventKind::refresh_rate, Json{{"from_hz", e.from_hz}, {"to_hz", e.to_hz}, {"requested", e.requested}}};
}

Detail detail(const events::PlaySummary& e) {
  return {EventKind::play_summary, Json{{"block", e.block},
                                        {"ended", e.ended},
                                        {"shots", e.shots},
                                        {"pocketed", e.pocketed},
                                        {"time_s", e.time_s},
                                        {"walked_m", e.walked_m},
                                        {"laps_physical", e.laps_physical},
                                        {"laps_virtual", e.laps_virtual},
                                        {"hand_error_m", e.hand_error_m}}};
}

Detail detail(const events::Strike& e) {
  return {EventKind::strike,
          Json{{"shot_index", e.shot_index}, {"ball", e.ball}, {"speed_m_s", e.speed_m_s}, {"miscue", e.miscue}}};
}
Detail detail(const events::Pocket& e) {
  return {EventKind::pocket, Json{{"shot_index", e.shot_index}, {"ball", e.ball}, {"pocket", e.pocket}}};
}

Detail detail(const events::QuestionnaireStart& e) {
  return {EventKind::questionnaire_start, Json{{"block", e.block},
                                               {"instrument", e.instrument},
                                               {"items", e.items},
                                               {"first_item", e.first_item}}};
}
Detail detail(const events::QuestionnaireEnd& e) {
  return {EventKind::questionnaire_end,
          Json{{"block", e.block}, {"instrument", e.instrument}, {"answered", e.answered}}};
}
Detail detail(const events::SharedGame& e) {
  return {EventKind::shared_game, Json{{"game_uuid", e.game_uuid},
                                       {"role", e.role},
                                       {"partner_initials", e.partner_initials},
                                       {"partner_version", e.partner_version},
                                       {"completed_shots", e.completed_shots}}};
}
Detail detail(const events::PartnerClock& e) {
  return {EventKind::partner_clock, Json{{"offset_ns", e.offset_ns},
                                         {"round_trip_ns", e.round_trip_ns},
                                         {"uncertainty_ns", e.uncertainty_ns},
                                         {"samples", e.samples}}};
}
Detail detail(const events::SharedShot& e) {
  return {EventKind::shared_shot, Json{{"shot_index", e.shot_index},
                                       {"shooter", e.shooter},
                                       {"local", e.local},
                                       {"same_events", e.same_events},
                                       {"rest_difference_m", e.rest_difference_m}}};
}
Detail detail(const events::SharedNetwork& e) {
  return {EventKind::shared_network, Json{{"rtt_ms", e.rtt_ms},
                                          {"loss", e.loss},
                                          {"poses_received", e.poses_received},
                                          {"poses_late", e.poses_late},
                                          {"poses_lost", e.poses_lost},
                                          {"bytes_sent", e.bytes_sent},
                                          {"bytes_received", e.bytes_received},
                                          {"dropped", e.dropped},
                                          {"disconnects", e.disconnects}}};
}
Detail detail(const events::PartnerLeft& e) {
  return {EventKind::partner_left, Json{{"completed_shots", e.completed_shots}}};
}
Detail detail(const events::PartnerBack& e) {
  return {EventKind::partner_back, Json{{"completed_shots", e.completed_shots}, {"away_s", e.away_s}}};
}

// The lapse keys are null when the method keeps λ fixed.
Detail detail(const events::Posterior& e) {
  const StepPosterior& p = e.value;
  const auto optional = [](const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); };
  return {EventKind::posterior, Json{{"staircase", e.staircase},
                                     {"step_index", e.step_index},
                                     {"pse_mean", p.pse_mean},
                                     {"pse_sd", p.pse_sd},
                                     {"slope_mean", p.slope_mean},
                                     {"slope_sd", p.slope_sd},
                                     {"lapse_mean", optional(p.lapse_mean)},
                                     {"lapse_sd", optional(p.lapse_sd)},
                                     {"entropy_nats", p.entropy_nats}}};
}

DataError bad_detail(std::string_view kind, const std::string& what) {
  return DataError{DataError::Kind::bad_input, "a stored " + std::string(kind) + " event " + what};
}

}  // namespace

std::string_view to_string(EventKind kind) {
  for (const auto& [k, name] : kind_names)
    if (k == kind) return name;
  return "unknown";
}

std::optional<EventKind> parse_event_kind(std::string_view text) {
  for (const auto& [k, name] : kind_names)
    if (name == text) return k;
  return std::nullopt;
}

EventRecord event_record(std::int64_t session_id, std::optional<std::int64_t> trial_id, std::int64_t t_ns,
                         const Event& event) {
  Detail d = std::visit([](const auto& e) { return detail(e); }, event);
  return EventRecord{session_id, trial_id, t_ns, std::string(to_string(d.kind)), std::move(d.text)};
}

Expected<events::SessionStart> parse_session_start(const std::string& detail_json) {
  const Json d = Json::parse(detail_json, nullptr, false);
  if (d.is_discarded() || !d.is_object()) return bad_detail("session_start", "is not a JSON object");
  events::SessionStart s;
  const auto number = d.find("participant_number");
  if (number != d.end()) {
    if (!number->is_number_unsigned()) return bad_detail("session_start", "has a participant_number that is not a whole number");
    s.participant_number = number->get<std::uint64_t>();
  }
  if (const auto msaa = d.find("msaa"); msaa != d.end() && msaa->is_number_unsigned())
    s.msaa = msaa->get<std::uint32_t>();
  if (const auto backend = d.find("backend"); backend != d.end() && backend->is_string())
    s.backend = backend->get<std::string>();
  return s;
}

std::optional<std::string> parse_run_options(const std::string& detail_json) {
  const Json d = Json::parse(detail_json, nullptr, false);
  if (d.is_discarded() || !d.is_object()) return std::nullopt;
  const auto o = d.find("run_options");
  if (o == d.end() || !o->is_object()) return std::nullopt;
  return o->dump();
}

Expected<events::Onset> parse_onset(const std::string& detail_json) {
  const Json d = Json::parse(detail_json, nullptr, false);
  events::Onset o;
  const bool ok = d.is_object() && d.contains("frame_index") && d["frame_index"].is_number_integer() &&
                  d.contains("head_pose") && read_pose(d["head_pose"], o.head_pose) && d.contains("stick_pose") &&
                  read_pose(d["stick_pose"], o.stick_pose);
  if (!ok) return bad_detail("onset", "lacks frame_index, head_pose or stick_pose (16 numbers each)");
  o.frame_index = d["frame_index"].get<std::int64_t>();
  if (const auto t = d.find("predicted_display_ns"); t != d.end() && t->is_number_integer())
    o.predicted_display_ns = t->get<std::int64_t>();
  if (const auto a = d.find("attempt"); a != d.end() && a->is_number_integer()) o.attempt = a->get<std::int64_t>();
  return o;
}

}  // namespace curvlab::harness::data
