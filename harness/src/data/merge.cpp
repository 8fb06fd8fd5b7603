// Pooling study files. Each input is ATTACHed read-only (a file: URI with
// mode=ro, so reading it can neither migrate nor checkpoint it) to a
// connection on a temporary copy of the output, and its sessions are copied
// with INSERT … SELECT, ids remapped through the natural keys the schema
// declares unique: protocols by sha256, participants by pseudonym, blocks
// and trials by their index within the session. The copy replaces the
// output by rename only when every input merged without conflict.
#include "curvlab/harness/data/merge.hpp"
#include "curvlab/harness/data/writer_lock.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/sha256.hpp"
#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/data/staging.hpp"

#include <nlohmann/json.hpp>
#include <sqlite3.h>
#include "curvlab/harness/platform/process.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <optional>

namespace curvlab::harness::data {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// `sql` with every "{s}" replaced by the schema name (main or src).
std::string in_schema(std::string sql, const std::string& schema) {
  for (auto at = sql.find("{s}"); at != std::string::npos; at = sql.find("{s}", at + schema.size()))
    sql.replace(at, 3, schema);
  return sql;
}

// One canonical text row per stored row, in a stable order; ids become the
// indices they stand for (trial_index, block_index, protocol sha256,
// pseudonym). session_number is left out: a merge may renumber. The events
// a merge writes itself (merged_from, session_renumbered) are provenance of
// the pooled copy, not something the session recorded, so they are left out.
constexpr std::array<const char*, 12> digest_queries = {
    "SELECT json_array(s.session_uuid, pr.sha256, p.pseudonym, s.software_version, s.software_commit, "
    "s.backend, s.renderer_device, s.renderer_driver, s.display_refresh_hz, s.seed, s.table_calibration, "
    "s.status, s.started_utc, s.ended_utc) FROM {s}.sessions s "
    "JOIN {s}.protocols pr ON pr.protocol_id = s.protocol_id "
    "JOIN {s}.participants p ON p.participant_id = s.participant_id WHERE s.session_id = ?1",
    "SELECT json_array(block_index, name, is_practice, settings) FROM {s}.blocks WHERE session_id = ?1 "
    "ORDER BY block_index",
    "SELECT json_array(t.trial_index, b.block_index, t.trial_in_block, t.conditions, t.stimulus, t.status, "
    "t.attempt, t.onset_ns, t.response_ns, t.response, t.rt_ns, t.response_device, t.completed_utc, "
    "t.end_reason) FROM {s}.trials t JOIN {s}.blocks b ON b.block_id = t.block_id WHERE t.session_id = ?1 "
    "ORDER BY t.trial_index",
    "SELECT json_array(x.staircase, x.step_index, t.trial_index, x.intensity, x.response_correct, "
    "x.is_reversal, x.next_intensity) FROM {s}.staircase_steps x LEFT JOIN {s}.trials t "
    "ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE x.session_id = ?1 "
    "ORDER BY x.staircase, x.step_index",
    "SELECT json_array(t.trial_index, x.frame_index, x.device, x.t_ns, x.lab_px_m, x.lab_py_m, x.lab_pz_m, "
    "x.lab_qx, x.lab_qy, x.lab_qz, x.lab_qw, x.position_valid, x.orientation_valid, hex(x.virtual_pose), "
    "x.physical_edge, x.virtual_edge, x.laps, x.anchor_fraction, x.coherence_error_m, x.coherence_error_rad) "
    "FROM {s}.tracking_samples x LEFT JOIN {s}.trials t ON t.trial_id = x.trial_id "
    "AND t.session_id = x.session_id WHERE x.session_id = ?1 ORDER BY x.sample_id",
    "SELECT json_array(t.trial_index, x.frame_index, x.t_ns, x.predicted_display_ns, x.cpu_time_ns, "
    "x.gpu_time_ns, x.dropped_frames, x.views, x.passes, x.draws, x.triangles, x.eye_width_px, "
    "x.eye_height_px, hex(x.eye_views), x.display_period_ns, x.late) FROM {s}.frames x "
    "LEFT JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id "
    "WHERE x.session_id = ?1 ORDER BY x.frame_id",
    "SELECT json_array(t.trial_index, x.frame_index, x.t_ns, x.combined_valid, x.combined_ox_m, "
    "x.combined_oy_m, x.combined_oz_m, x.combined_dx, x.combined_dy, x.combined_dz, x.left_valid, "
    "x.left_confidence, x.left_ox_m, x.left_oy_m, x.left_oz_m, x.left_dx, x.left_dy, x.left_dz, "
    "x.right_valid, x.right_confidence, x.right_ox_m, x.right_oy_m, x.right_oz_m, x.right_dx, "
    "x.right_dy, x.right_dz, x.vergence_rad, x.vergence_distance_m) FROM {s}.gaze_samples x LEFT "
    "JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE "
    "x.session_id = ?1 ORDER BY x.gaze_id",
    "SELECT json_array(t.trial_index, x.shot_index, x.t_ns, x.rest_ns, x.player, x.ball, x.aim_x, x.aim_z, x.speed_m_s, x.cue_speed_m_s, x.tip_side, x.tip_height, x.miscue, x.cue_pose, x.table_settings, x.before_state, x.shot, x.events, x.rest_state, x.pocketed, x.event_count) FROM {s}.shots x "
    "JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE x.session_id = ?1 "
    "ORDER BY t.trial_index, x.shot_index",
    "SELECT json_array(t.trial_index, x.instrument, x.item_index, x.item_id, x.item_text, x.value, x.label, "
    "x.shown_ns, x.t_ns, x.rt_ms, x.device) FROM {s}.questionnaire_answers x "
    "JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE x.session_id = ?1 "
    "ORDER BY t.trial_index, x.item_index",
    "SELECT json_array(t.trial_index, x.instrument, x.subscale_index, x.subscale, x.rule, x.weight, x.items, "
    "x.answered, x.raw, x.score) FROM {s}.questionnaire_scores x "
    "JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE x.session_id = ?1 "
    "ORDER BY t.trial_index, x.subscale_index",
    "SELECT json_array(t.trial_index, x.frame_index, x.device, x.t_ns, hex(x.virtual_pose), x.tracked, "
    "x.extrapolated, x.sample_age_ns, x.distance_m) FROM {s}.partner_samples x LEFT JOIN {s}.trials t "
    "ON t.trial_id = x.trial_id AND t.session_id = x.session_id WHERE x.session_id = ?1 ORDER BY x.sample_id",
    "SELECT json_array(t.trial_index, x.t_ns, x.kind, x.detail) FROM {s}.events x "
    "LEFT JOIN {s}.trials t ON t.trial_id = x.trial_id AND t.session_id = x.session_id "
    "WHERE x.session_id = ?1 AND x.kind NOT IN ('merged_from', 'session_renumbered') ORDER BY x.event_id",
};

std::string digest_session(Connection& c, const std::string& schema, std::int64_t session_id) {
  Sha256 digest;
  for (std::size_t q = 0; q < digest_queries.size(); ++q) {
    const std::string table_mark = std::to_string(q) + "#\n";
    digest.add(table_mark);
    Statement s(c, in_schema(digest_queries[q], schema));
    s.bind(1, session_id);
    while (s.step()) {
      digest.add(s.column_text(0));
      digest.add("\n");
    }
  }
  return digest.hex();
}

// "status interrupted, 3 of 8 trials completed, 1200 tracking samples".
std::string describe_session(Connection& c, const std::string& schema, std::int64_t session_id) {
  Statement s(c, in_schema("SELECT s.status, (SELECT COUNT(*) FROM {s}.trials t WHERE t.session_id = ?1 AND "
                           "t.status = 'completed'), (SELECT COUNT(*) FROM {s}.trials t WHERE t.session_id = ?1), "
                           "(SELECT COUNT(*) FROM {s}.tracking_samples x WHERE x.session_id = ?1) "
                           "FROM {s}.sessions s WHERE s.session_id = ?1",
                           schema));
  s.bind(1, session_id);
  if (!s.step()) return "missing";
  return "status " + s.column_text(0) + ", " + std::to_string(s.column_int(1)) + " of " +
         std::to_string(s.column_int(2)) + " trials completed, " + std::to_string(s.column_int(3)) +
         " tracking samples";
}

// A file: URI that opens `path` read-only (RFC 3986 percent-encoding).
std::string read_only_uri(const std::string& path) {
  return file_uri(path, needs_immutable_open(path) ? "mode=ro&immutable=1" : "mode=ro");
}

// An input or existing output must be a curvlab file of the current schema:
// a merge never migrates a file (migration would give an older file's
// sessions new random UUIDs each time, breaking idempotence).
Expected<Done> check_current_file(const std::string& path, const std::string& role) {
  auto db = Database::open(path, OpenMode::read_only);
  if (!db) return db.error();
  const std::int64_t version = stored_schema_version(path);
  if (version >= 0 && version < current_schema_version)
    return DataError{DataError::Kind::bad_input,
                     path + ": " + role + " has schema version " + std::to_string(version) +
                         "; merge reads files without changing them and needs version " +
                         std::to_string(current_schema_version) +
                         ". Upgrade it once in place, which gives each of its sessions a UUID, with "
                         "curvlab upgrade --db " + path + ", then merge again"};
  return Done{};
}

std::string source_of(Connection& c, std::int64_t session_id, const std::string& fallback) {
  Statement s(c, "SELECT json_extract(detail, '$.source_file') FROM main.events WHERE session_id = ?1 "
                 "AND kind = 'merged_from' ORDER BY event_id DESC LIMIT 1");
  s.bind(1, session_id);
  if (s.step() && !s.is_null(0)) return s.column_text(0);
  return fallback;
}

// Refuses a second text under one protocol name unless allowed.
Expected<Done> check_protocol_versions(Connection& c, const MergeOptions& opts, const std::string& input) {
  if (opts.allow_protocol_versions) return Done{};
  Statement s(c,
              "SELECT sp.name, sp.sha256, mp.sha256, mp.protocol_id FROM src.protocols sp "
              "JOIN main.protocols mp ON mp.name = sp.name AND mp.sha256 <> sp.sha256 "
              "UNION ALL SELECT a.name, a.sha256, b.sha256, NULL FROM src.protocols a "
              "JOIN src.protocols b ON b.name = a.name AND b.sha256 > a.sha256 LIMIT 1");
  if (!s.step()) return Done{};
  std::string other = input;
  if (!s.is_null(3)) {
    Statement user(c, "SELECT session_id FROM main.sessions WHERE protocol_id = ?1 LIMIT 1");
    user.bind(1, s.column_int(3));
    other = user.step() ? source_of(c, user.column_int(0), opts.out_path) : opts.out_path;
  }
  return DataError{DataError::Kind::bad_input,
                   input + ": protocol \"" + s.column_text(0) + "\" has sha256 " + s.column_text(1) +
                       ", but " + other + " has a different text under the same name (sha256 " +
                       s.column_text(2) +
                       "). Pooling sessions that ran different versions of a protocol needs "
                       "--allow-protocol-versions (each session keeps the text it ran)"};
}

void copy_protocols_and_participants(Connection& c) {
  // source_path as its file name alone: files written before only the name
  // was stored hold the folder, which can name a person. rtrim leaves the
  // folder part (up to the last '/'), and the name follows it.
  c.exec("INSERT INTO main.protocols (name, sha256, text, source_path) SELECT name, sha256, text, "
         "substr(source_path, length(rtrim(source_path, replace(source_path, '/', ''))) + 1) "
         "FROM src.protocols WHERE sha256 NOT IN (SELECT sha256 FROM main.protocols) ORDER BY protocol_id");
  c.exec("INSERT INTO main.participants (pseudonym, ipd_m, dominant_eye, created_utc) SELECT pseudonym, ipd_m, "
         "dominant_eye, created_utc FROM src.participants WHERE pseudonym NOT IN "
         "(SELECT pseudonym FROM main.participants) ORDER BY participant_id");
}

struct SourceSession {
  std::int64_t id = 0;
  std::string uuid;
  std::string pseudonym;
  std::int64_t number = 0;
};

Expected<std::vector<SourceSession>> source_sessions(Connection& c, const std::string& input) {
  Statement s(c, "SELECT s.session_id, s.session_uuid, p.pseudonym, s.session_number FROM src.sessions s "
                 "JOIN src.participants p ON p.participant_id = s.participant_id ORDER BY s.session_id");
  std::vector<SourceSession> out;
  while (s.step()) {
    if (s.is_null(1))
      return DataError{DataError::Kind::bad_input,
                       input + ": session " + std::to_string(s.column_int(0)) +
                           " has no session_uuid, so it cannot be matched across files"};
    out.push_back({s.column_int(0), s.column_text(1), s.column_text(2), s.column_int(3)});
  }
  return out;
}

std::optional<std::int64_t> study_session_with_uuid(Connection& c, const std::string& uuid) {
  Statement s(c, "SELECT session_id FROM main.sessions WHERE session_uuid = ?1");
  s.bind(1, std::string_view(uuid));
  if (s.step()) return s.column_int(0);
  return std::nullopt;
}

// The session's number in the study, and the UUID of the session that
// already holds its own number there (empty when free).
std::pair<std::int64_t, std::string> free_session_number(Connection& c, const SourceSession& src) {
  Statement s(c, "SELECT s.session_uuid, (SELECT MAX(o.session_number) FROM main.sessions o "
                 "WHERE o.participant_id = s.participant_id) FROM main.sessions s JOIN main.participants p "
                 "ON p.participant_id = s.participant_id WHERE p.pseudonym = ?1 AND s.session_number = ?2");
  s.bind(1, std::string_view(src.pseudonym)).bind(2, src.number);
  if (!s.step()) return {src.number, ""};
  return {s.column_int(1) + 1, s.column_opt_text(0).value_or("")};
}

// The trial of a child row in the study: same session, same trial_index.
constexpr const char* mapped_trial =
    " LEFT JOIN src.trials st ON st.trial_id = x.trial_id AND st.session_id = x.session_id"
    " LEFT JOIN main.trials mt ON mt.session_id = ?2 AND mt.trial_index = st.trial_index";

// The copies of one session's rows, each with the summary count its rows add to.
struct RowCopy {
  const char* sql;
  std::int64_t MergeInputReport::*counted = nullptr;
};

constexpr std::array<RowCopy, 11> copy_statements = {{
    {"INSERT INTO main.blocks (session_id, block_index, name, is_practice, settings) SELECT ?2, block_index, "
    "name, is_practice, settings FROM src.blocks WHERE session_id = ?1 ORDER BY block_id", nullptr},
    {"INSERT INTO main.trials (session_id, block_id, trial_index, trial_in_block, conditions, stimulus, status, "
    "attempt, onset_ns, response_ns, response, rt_ns, response_device, completed_utc, end_reason) "
    "SELECT ?2, mb.block_id, x.trial_index, x.trial_in_block, x.conditions, x.stimulus, x.status, x.attempt, "
    "x.onset_ns, x.response_ns, x.response, x.rt_ns, x.response_device, x.completed_utc, x.end_reason "
    "FROM src.trials x JOIN src.blocks sb ON sb.block_id = x.block_id JOIN main.blocks mb "
    "ON mb.session_id = ?2 AND mb.block_index = sb.block_index WHERE x.session_id = ?1 ORDER BY x.trial_id", &MergeInputReport::trials},
    {"INSERT INTO main.staircase_steps (session_id, staircase, step_index, trial_id, intensity, "
    "response_correct, is_reversal, next_intensity) SELECT ?2, x.staircase, x.step_index, mt.trial_id, "
    "x.intensity, x.response_correct, x.is_reversal, x.next_intensity FROM src.staircase_steps x{trial} "
    "WHERE x.session_id = ?1 ORDER BY x.step_id", nullptr},
    {"INSERT INTO main.tracking_samples (session_id, trial_id, frame_index, device, t_ns, lab_px_m, lab_py_m, "
    "lab_pz_m, lab_qx, lab_qy, lab_qz, lab_qw, position_valid, orientation_valid, virtual_pose, "
    "physical_edge, virtual_edge, laps, anchor_fraction, coherence_error_m, coherence_error_rad) "
    "SELECT ?2, mt.trial_id, x.frame_index, x.device, x.t_ns, x.lab_px_m, x.lab_py_m, x.lab_pz_m, x.lab_qx, "
    "x.lab_qy, x.lab_qz, x.lab_qw, x.position_valid, x.orientation_valid, x.virtual_pose, x.physical_edge, "
    "x.virtual_edge, x.laps, x.anchor_fraction, x.coherence_error_m, x.coherence_error_rad "
    "FROM src.tracking_samples x{trial} WHERE x.session_id = ?1 ORDER BY x.sample_id", &MergeInputReport::samples},
    {"INSERT INTO main.frames (session_id, trial_id, frame_index, t_ns, predicted_display_ns, cpu_time_ns, "
    "gpu_time_ns, dropped_frames, views, passes, draws, triangles, eye_width_px, eye_height_px, eye_views, "
    "display_period_ns, late) SELECT ?2, mt.trial_id, x.frame_index, x.t_ns, x.predicted_display_ns, "
    "x.cpu_time_ns, x.gpu_time_ns, x.dropped_frames, x.views, x.passes, x.draws, x.triangles, x.eye_width_px, "
    "x.eye_height_px, x.eye_views, x.display_period_ns, x.late FROM src.frames x{trial} "
    "WHERE x.session_id = ?1 ORDER BY x.frame_id", &MergeInputReport::frames},
    {"INSERT INTO main.gaze_samples (session_id, trial_id, frame_index, t_ns, combined_valid, "
    "combined_ox_m, combined_oy_m, combined_oz_m, combined_dx, combined_dy, combined_dz, "
    "left_valid, left_confidence, left_ox_m, left_oy_m, left_oz_m, left_dx, left_dy, left_dz, "
    "right_valid, right_confidence, right_ox_m, right_oy_m, right_oz_m, right_dx, right_dy, "
    "right_dz, vergence_rad, vergence_distance_m) SELECT ?2, mt.trial_id, x.frame_index, x.t_ns, "
    "x.combined_valid, x.combined_ox_m, x.combined_oy_m, x.combined_oz_m, x.combined_dx, "
    "x.combined_dy, x.combined_dz, x.left_valid, x.left_confidence, x.left_ox_m, x.left_oy_m, "
    "x.left_oz_m, x.left_dx, x.left_dy, x.left_dz, x.right_valid, x.right_confidence, x.right_ox_m, "
    "x.right_oy_m, x.right_oz_m, x.right_dx, x.right_dy, x.right_dz, x.vergence_rad, "
    "x.vergence_distance_m FROM src.gaze_samples x{trial} WHERE x.session_id = ?1 ORDER BY "
    "x.gaze_id", nullptr},
    {"INSERT INTO main.shots (session_id, trial_id, shot_index, t_ns, rest_ns, player, ball, aim_x, aim_z, speed_m_s, cue_speed_m_s, tip_side, tip_height, miscue, cue_pose, table_settings, before_state, shot, events, rest_state, pocketed, event_count) SELECT ?2, mt.trial_id, x.shot_index, x.t_ns, x.rest_ns, x.player, x.ball, x.aim_x, x.aim_z, x.speed_m_s, x.cue_speed_m_s, x.tip_side, x.tip_height, x.miscue, x.cue_pose, x.table_settings, x.before_state, x.shot, x.events, x.rest_state, x.pocketed, x.event_count "
    "FROM src.shots x{trial} WHERE x.session_id = ?1 ORDER BY x.shot_id", nullptr},
    {"INSERT INTO main.questionnaire_answers (session_id, trial_id, instrument, item_index, item_id, item_text, "
    "value, label, shown_ns, t_ns, rt_ms, device) SELECT ?2, mt.trial_id, x.instrument, x.item_index, x.item_id, "
    "x.item_text, x.value, x.label, x.shown_ns, x.t_ns, x.rt_ms, x.device "
    "FROM src.questionnaire_answers x{trial} WHERE x.session_id = ?1 ORDER BY x.answer_id", nullptr},
    {"INSERT INTO main.questionnaire_scores (session_id, trial_id, instrument, subscale_index, subscale, rule, "
    "weight, items, answered, raw, score) SELECT ?2, mt.trial_id, x.instrument, x.subscale_index, x.subscale, "
    "x.rule, x.weight, x.items, x.answered, x.raw, x.score "
    "FROM src.questionnaire_scores x{trial} WHERE x.session_id = ?1 ORDER BY x.score_id", nullptr},
    {"INSERT INTO main.partner_samples (session_id, trial_id, frame_index, device, t_ns, virtual_pose, tracked, "
    "extrapolated, sample_age_ns, distance_m) SELECT ?2, mt.trial_id, x.frame_index, x.device, x.t_ns, "
    "x.virtual_pose, x.tracked, x.extrapolated, x.sample_age_ns, x.distance_m "
    "FROM src.partner_samples x{trial} WHERE x.session_id = ?1 ORDER BY x.sample_id", nullptr},
    {"INSERT INTO main.events (session_id, trial_id, t_ns, kind, detail) SELECT ?2, mt.trial_id, x.t_ns, "
    "x.kind, x.detail FROM src.events x{trial} WHERE x.session_id = ?1 ORDER BY x.event_id", nullptr},
}};

std::string with_trial_mapping(std::string sql) {
  const auto at = sql.find("{trial}");
  if (at != std::string::npos) sql.replace(at, 7, mapped_trial);
  return sql;
}

std::int64_t insert_session_row(Connection& c, std::int64_t source_id, std::int64_t number) {
  Statement s(c,
              "INSERT INTO main.sessions (protocol_id, participant_id, session_number, software_version, "
              "software_commit, backend, renderer_device, renderer_driver, display_refresh_hz, seed, "
              "table_calibration, status, started_utc, ended_utc, session_uuid) SELECT mp.protocol_id, "
              "mpa.participant_id, ?2, s.software_version, s.software_commit, s.backend, s.renderer_device, "
              "s.renderer_driver, s.display_refresh_hz, s.seed, s.table_calibration, s.status, s.started_utc, "
              "s.ended_utc, s.session_uuid FROM src.sessions s "
              "JOIN src.protocols sp ON sp.protocol_id = s.protocol_id "
              "JOIN main.protocols mp ON mp.sha256 = sp.sha256 "
              "JOIN src.participants spa ON spa.participant_id = s.participant_id "
              "JOIN main.participants mpa ON mpa.pseudonym = spa.pseudonym WHERE s.session_id = ?1");
  s.bind(1, source_id).bind(2, number).run();
  return c.last_insert_rowid();
}

// An event of the merge itself, after the session's last recorded event.
void add_merge_event(Connection& c, std::int64_t session_id, const char* kind, const Json& detail) {
  Statement s(c, "INSERT INTO main.events (session_id, trial_id, t_ns, kind, detail) VALUES (?1, NULL, "
                 "(SELECT COALESCE(MAX(t_ns), 0) FROM main.events WHERE session_id = ?1), ?2, "
                 "json_set(?3, '$.merged_utc', strftime('%Y-%m-%dT%H:%M:%fZ', 'now')))");
  s.bind(1, session_id).bind(2, std::string_view(kind)).bind(3, detail.dump()).run();
}

Json schema_history(Connection& c) {
  Json rows = Json::array();
  Statement s(c, "SELECT version, applied_utc, note FROM src.schema_migrations ORDER BY version");
  while (s.step())
    rows.push_back({{"version", s.column_int(0)}, {"applied_utc", s.column_text(1)}, {"note", s.column_text(2)}});
  return rows;
}

void add_session(Connection& c, const SourceSession& src, const std::string& input, const Json& history,
                 MergeInputReport& report) {
  const auto [number, holder] = free_session_number(c, src);
  const std::int64_t id = insert_session_row(c, src.id, number);
  for (const auto& copy : copy_statements) {
    Statement s(c, with_trial_mapping(copy.sql));
    s.bind(1, src.id).bind(2, id).run();
    if (copy.counted != nullptr) report.*copy.counted += c.changes();
  }
  // The file name, not its folder: a folder can name a person.
  const std::string source_file = fs::path(input).filename().string();
  add_merge_event(c, id, "merged_from",
                  {{"source_file", source_file},
                   {"source_session_id", src.id},
                   {"source_session_number", src.number},
                   {"source_schema_migrations", history}});
  if (!holder.empty()) {
    add_merge_event(c, id, "session_renumbered",
                    {{"from", src.number}, {"to", number}, {"source_file", source_file}, {"number_held_by", holder}});
    ++report.sessions_renumbered;
  }
  ++report.sessions_added;
}

void compare_session(Connection& c, const SourceSession& src, std::int64_t study_id, const std::string& input,
                     const MergeOptions& opts, MergeReport& report) {
  if (digest_session(c, "main", study_id) == digest_session(c, "src", src.id)) {
    ++report.inputs.back().sessions_skipped;
    return;
  }
  ++report.inputs.back().sessions_conflicting;
  const std::string first = source_of(c, study_id, opts.out_path);
  const std::string ours = describe_session(c, "main", study_id);
  const std::string theirs = describe_session(c, "src", src.id);
  const std::string advice =
      ours == theirs ? "The rows differ although status and counts agree: one copy was edited, or two "
                       "recordings carry one UUID; merge only the right one"
                     : "If one is a copy taken before the session was resumed, merge only the later file "
                       "(when the study already holds the earlier copy, build the study again from the "
                       "current files)";
  report.conflicts.push_back({src.uuid, first, input, first + ": " + ours + "; " + input + ": " + theirs + ". " + advice});
}

Expected<Done> merge_attached(Connection& c, const std::string& input, const MergeOptions& opts,
                              MergeReport& report) {
  if (auto ok = check_protocol_versions(c, opts, input); !ok) return ok.error();
  auto sessions = source_sessions(c, input);
  if (!sessions) return sessions.error();
  copy_protocols_and_participants(c);
  const Json history = schema_history(c);
  for (const SourceSession& src : sessions.value()) {
    if (auto study_id = study_session_with_uuid(c, src.uuid))
      compare_session(c, src, *study_id, input, opts, report);
    else
      add_session(c, src, input, history, report.inputs.back());
  }
  return Done{};
}

// A full disk while merging is the output's disk, not the input's; nothing
// is resumed: the merge is all or nothing.
DataError output_disk_full(const std::string& work, const std::string& input, const std::string& out) {
  return DataError{DataError::Kind::disk_full,
                   out + ": the disk is full (the merge's work file " + work + " could not grow while adding " +
                       input + "); nothing was changed. Free space on the disk holding " + out +
                       " and merge again"};
}

// An input whose session a live process is writing would be copied in the
// middle of that session (and later refused as a conflict when merged
// whole).
Expected<Done> check_not_live(const std::string& input) {
  const auto writer = WriterLock::file_writer(input);
  if (!writer) return Done{};
  const std::string what = writer->first > 0 ? "session " + std::to_string(writer->first) + " is being written by "
                                             : "the file is being replaced by ";
  return DataError{DataError::Kind::in_use,
                   input + ": " + what + describe(writer->second) + "; merging it now would copy that session "
                   "half-done, so nothing was merged. Merge it when the session has ended (a session whose process "
                   "died can be merged at once)"};
}

Expected<Done> merge_one(Database& work, const std::string& input, const MergeOptions& opts,
                         MergeReport& report) {
  if (auto ok = check_current_file(input, "input"); !ok) return ok.error();
  report.inputs.push_back({input});
  Connection& c = work.connection();
  try {
    Statement attach(c, "ATTACH DATABASE ?1 AS src");
    attach.bind(1, read_only_uri(input)).run();
  } catch (const SqliteFailure& f) {
    return to_data_error(f, input);
  }
  Expected<Done> merged = Done{};
  try {
    Transaction txn(c);
    merged = merge_attached(c, input, opts, report);
    if (merged) txn.commit();
  } catch (const SqliteFailure& f) {
    merged = (f.code & 0xff) == SQLITE_FULL ? output_disk_full(work.path(), input, opts.out_path)
                                            : to_data_error(f, input);
  }
  try {
    c.exec("DETACH DATABASE src");
  } catch (const SqliteFailure& f) {
    if (merged) merged = to_data_error(f, input);
  }
  return merged;
}

// Removes the temporary output (and its journals) unless kept.
class TempOutput {
 public:
  explicit TempOutput(std::string path) : path_(std::move(path)) { remove_database_files(path_); }
  ~TempOutput() {
    if (!kept_) remove_database_files(path_);
  }
  TempOutput(const TempOutput&) = delete;
  TempOutput& operator=(const TempOutput&) = delete;
  const std::string& path() const { return path_; }
  void keep() { kept_ = true; }

 private:
  std::string path_;
  bool kept_ = false;
};

// Copies the existing output into `tmp` with SQLite's online backup, after
// folding its write-ahead log into it (so no stale log outlives the rename).
Expected<Done> copy_existing_output(const std::string& out, const std::string& tmp) {
  if (auto ok = check_current_file(out, "the output"); !ok) return ok.error();
  try {
    {
      Connection flush = Connection::open(out, OpenFlags::read_write);
      configure_connection(flush, true);
      flush.exec("PRAGMA wal_checkpoint(TRUNCATE)");
    }
    Connection from = Connection::open(out, OpenFlags::read_only);
    Connection to = Connection::open(tmp, OpenFlags::read_write_create);
    sqlite3_backup* backup = sqlite3_backup_init(to.get(), "main", from.get(), "main");
    if (backup == nullptr) to.fail(sqlite3_errcode(to.get()), "backup of " + out);
    const int rc = sqlite3_backup_step(backup, -1);
    sqlite3_backup_finish(backup);
    if (rc != SQLITE_DONE) to.fail(rc, "backup of " + out);
  } catch (const SqliteFailure& f) {
    return to_data_error(f, out);
  }
  return Done{};
}

Expected<Done> check_inputs(const MergeOptions& opts) {
  if (opts.out_path.empty()) return DataError{DataError::Kind::usage, "merge: no output file given (--out)"};
  if (opts.inputs.empty()) return DataError{DataError::Kind::usage, "merge: no input files given"};
  std::error_code ec;
  for (const std::string& input : opts.inputs) {
    if (!fs::is_regular_file(input, ec))
      return DataError{DataError::Kind::not_found, input + ": no such database file"};
    if (fs::exists(opts.out_path, ec) && fs::equivalent(input, opts.out_path, ec))
      return DataError{DataError::Kind::usage, input + ": is the output file itself; give it only as --out"};
    if (auto ok = check_not_live(input); !ok) return ok.error();
  }
  return Done{};
}

// Merges every input into the temporary copy; true when anything was added.
// The work file grows to about the output plus every input.
SpaceNeeded space_for(const MergeOptions& opts) {
  std::error_code ec;
  std::uint64_t bytes = 1u << 20;
  for (const std::string& input : opts.inputs) {
    const auto size = fs::file_size(input, ec);
    if (!ec) bytes += size;
    const auto wal = fs::file_size(input + "-wal", ec);
    if (!ec) bytes += wal;
  }
  return {bytes, "merging these files"};
}

Expected<bool> merge_into(const std::string& tmp, bool existed, const MergeOptions& opts, MergeReport& report) {
  auto work = Database::open(tmp, existed ? OpenMode::open_existing : OpenMode::create_or_open, space_for(opts));
  if (!work) return work.error();
  Connection& c = work.value().connection();
  const std::int64_t before = sqlite3_total_changes64(c.get());
  for (const std::string& input : opts.inputs)
    if (auto ok = merge_one(work.value(), input, opts, report); !ok) return ok.error();
  const bool changed = sqlite3_total_changes64(c.get()) != before;
  try {
    c.exec("PRAGMA journal_mode = DELETE");  // one self-contained file to rename
  } catch (const SqliteFailure& f) {
    return to_data_error(f, tmp);
  }
  return changed || !existed;
}

}  // namespace

Expected<MergeReport> merge_databases(const MergeOptions& opts) {
  if (auto ok = check_inputs(opts); !ok) return ok.error();
  // The output is replaced by a rename: never under a live session's writer.
  auto lock = WriterLock::for_replacing(opts.out_path);
  if (!lock) return lock.error();
  std::error_code ec;
  const bool existed = !lock->created_file();
  // A merge killed before it renamed its work leaves OUT.merging-PID behind.
  const fs::path out(opts.out_path);
  remove_stale_staging(out.parent_path().string(), out.filename().string() + ".merging-", StagingKind::database);
  TempOutput tmp(opts.out_path + ".merging-" + std::to_string(platform::process_id()));
  if (existed)
    if (auto ok = copy_existing_output(opts.out_path, tmp.path()); !ok) return ok.error();
  MergeReport report;
  auto changed = merge_into(tmp.path(), existed, opts, report);
  if (!changed) return changed.error();
  if (!report.conflicts.empty() || !changed.value()) return report;
  fs::rename(tmp.path(), opts.out_path, ec);
  if (ec)
    return DataError{DataError::Kind::io, "cannot move " + tmp.path() + " to " + opts.out_path + ": " + ec.message()};
  tmp.keep();
  report.output_changed = true;
  return report;
}

Expected<std::vector<std::string>> database_files_in(const std::string& dir) {
  std::error_code ec;
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (std::error_code entry_ec; entry.is_regular_file(entry_ec) && entry.path().extension() == ".sqlite")
      files.push_back(entry.path().string());
  if (ec) return DataError{DataError::Kind::io, dir + ": cannot list the folder: " + ec.message()};
  if (files.empty()) return DataError{DataError::Kind::not_found, dir + ": no .sqlite files in this folder"};
  std::sort(files.begin(), files.end());
  return files;
}

Expected<std::string> session_content_digest(const std::string& db_path, const std::string& session_uuid) {
  auto db = Database::open(db_path, OpenMode::read_only);
  if (!db) return db.error();
  try {
    Connection& c = db.value().connection();
    auto id = study_session_with_uuid(c, session_uuid);
    if (!id) return DataError{DataError::Kind::not_found, db_path + ": no session with UUID " + session_uuid};
    return digest_session(c, "main", *id);
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db_path);
  }
}

}  // namespace curvlab::harness::data
