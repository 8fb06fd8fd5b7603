#include "curvlab/harness/data/session_reader.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/session_list.hpp"
#include "curvlab/harness/data/sqlite.hpp"

#include <nlohmann/json.hpp>

#include <cstring>
#include <span>

namespace curvlab::harness::data {
namespace {

using Json = nlohmann::json;
using Kind = DataError::Kind;

// Runs `body`; SQLite failures become DataError values naming the file.
template <class F>
auto guarded(Database& db, F&& body) -> decltype(body()) {
  try {
    return body();
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, db.path());
  } catch (const nlohmann::json::exception& e) {
    // A stored JSON text of the wrong shape: the file was edited or damaged.
    return corrupt_file_error(db.path(), std::string("a stored JSON value has the wrong shape (") + e.what() + ")");
  }
}

DataError corrupt(Database& db, const std::string& what) {
  return DataError{Kind::corrupt, db.path() + ": " + what};
}

DominantEye parse_eye(const std::string& s) {
  if (s == "left") return DominantEye::left;
  if (s == "right") return DominantEye::right;
  return DominantEye::unknown;
}

// Copies a blob of exactly N doubles; false when its size differs.
template <std::size_t N>
bool read_doubles(std::span<const std::byte> blob, std::array<double, N>& out) {
  if (blob.size() != N * sizeof(double)) return false;
  std::memcpy(out.data(), blob.data(), blob.size());
  return true;
}


}  // namespace

Expected<SessionProvenance> read_session_provenance(Database& db, std::int64_t session_id) {
  return guarded(db, [&]() -> Expected<SessionProvenance> {
    auto& c = db.connection();
    Statement s(c,
                "SELECT pr.text, pr.source_path, p.pseudonym, p.dominant_eye, p.ipd_m, se.seed, se.status, "
                "se.backend, se.table_calibration FROM sessions se "
                "JOIN protocols pr ON pr.protocol_id = se.protocol_id "
                "JOIN participants p ON p.participant_id = se.participant_id WHERE se.session_id = ?1");
    s.bind(1, session_id);
    if (!s.step()) return missing_session_error(db, session_id);
    SessionProvenance out;
    out.session_id = session_id;
    out.protocol_text = s.column_text(0);
    out.protocol_source_path = s.column_opt_text(1);
    out.pseudonym = s.column_text(2);
    out.dominant_eye = parse_eye(s.column_text(3));
    out.ipd_m = s.column_opt_double(4);
    out.seed = s.column_int(5);
    const auto status = parse_session_status(s.column_text(6));
    if (!status) return corrupt(db, "session " + std::to_string(session_id) + " has an unknown status");
    out.status = *status;
    out.backend = parse_backend(s.column_text(7));
    out.table_calibration_json = s.column_opt_text(8);

    Statement last(c, "SELECT MAX(COALESCE((SELECT MAX(t_ns) FROM frames WHERE session_id = ?1), 0), "
                      "COALESCE((SELECT MAX(t_ns) FROM events WHERE session_id = ?1), 0))");
    last.bind(1, session_id);
    if (last.step()) out.last_t_ns = last.column_int(0);

    Statement ev(c, "SELECT kind, detail FROM events WHERE session_id = ?1 AND kind IN (?2, ?3, ?4) "
                    "ORDER BY event_id");
    ev.bind(1, session_id)
        .bind_static(2, to_string(EventKind::session_start))
        .bind_static(3, to_string(EventKind::observer))
        .bind_static(4, to_string(EventKind::resume));
    while (ev.step()) {
      const auto kind = parse_event_kind(ev.column_text(0));
      if (kind == EventKind::session_start) {
        auto start = parse_session_start(ev.column_text(1));
        if (!start) return corrupt_file_error(db.path(), start.error().message);
        out.participant_number = start->participant_number;
        out.msaa = start->msaa;
        out.run_options_json = parse_run_options(ev.column_text(1));
        continue;
      }
      if (kind == EventKind::resume) {
        if (auto options = parse_run_options(ev.column_text(1))) out.run_options_json = std::move(options);
        continue;
      }
      out.observer = StoredObserver{std::string(ev.column_text(1))};
    }
    return out;
  });
}

Expected<std::vector<StoredTrial>> read_trial_list(Database& db, std::int64_t session_id) {
  return guarded(db, [&]() -> Expected<std::vector<StoredTrial>> {
    Statement s(db.connection(), "SELECT trial_id, trial_index, conditions FROM trials WHERE session_id = ?1 "
                                 "ORDER BY trial_index");
    s.bind(1, session_id);
    std::vector<StoredTrial> out;
    while (s.step()) out.push_back({s.column_int(0), s.column_int(1), s.column_text(2)});
    return out;
  });
}

Expected<std::int64_t> read_last_frame_index(Database& db, std::int64_t session_id) {
  return guarded(db, [&]() -> Expected<std::int64_t> {
    Statement s(db.connection(), "SELECT COALESCE(MAX(frame_index), -1) FROM frames WHERE session_id = ?1");
    s.bind(1, session_id);
    return s.step() ? s.column_int(0) : std::int64_t{-1};
  });
}

Expected<std::vector<StoredStaircaseResponse>> read_staircase_responses(Database& db,
                                                                        std::int64_t session_id) {
  return guarded(db, [&]() -> Expected<std::vector<StoredStaircaseResponse>> {
    Statement s(db.connection(), "SELECT trial_id, response_correct FROM staircase_steps "
                                 "WHERE session_id = ?1 AND trial_id IS NOT NULL ORDER BY step_id");
    s.bind(1, session_id);
    std::vector<StoredStaircaseResponse> out;
    while (s.step()) {
      StoredStaircaseResponse r{s.column_int(0), std::nullopt};
      if (!s.is_null(1)) r.response_correct = s.column_int(1) != 0;
      out.push_back(r);
    }
    return out;
  });
}

Expected<std::int64_t> read_trial_id(Database& db, std::int64_t session_id, std::int64_t trial_index) {
  return guarded(db, [&]() -> Expected<std::int64_t> {
    Statement s(db.connection(), "SELECT trial_id FROM trials WHERE session_id = ?1 AND trial_index = ?2");
    s.bind(1, session_id).bind(2, trial_index);
    if (!s.step())
      return DataError{Kind::not_found, db.path() + ": no trial " + std::to_string(trial_index) +
                                            " in session " + std::to_string(session_id)};
    return s.column_int(0);
  });
}

Expected<std::vector<ShotRecord>> read_shots(Database& db, std::int64_t trial_id) {
  return guarded(db, [&]() -> Expected<std::vector<ShotRecord>> {
    Statement s(db.connection(),
                "SELECT session_id, trial_id, shot_index, t_ns, rest_ns, player, ball, aim_x, aim_z, speed_m_s, "
                "cue_speed_m_s, tip_side, tip_height, miscue, cue_pose, table_settings, before_state, shot, "
                "events, rest_state, pocketed, event_count FROM shots WHERE trial_id = ?1 ORDER BY shot_index");
    s.bind(1, trial_id);
    std::vector<ShotRecord> out;
    while (s.step()) {
      ShotRecord r;
      s.columns(r.session_id, r.trial_id, r.shot_index, r.t_ns, r.rest_ns, r.player, r.ball, r.aim_x, r.aim_z,
                r.speed_m_s, r.cue_speed_m_s, r.tip_side, r.tip_height, r.miscue, r.cue_pose, r.table_settings,
                r.before_state, r.shot, r.events, r.rest_state, r.pocketed, r.event_count);
      out.push_back(std::move(r));
    }
    return out;
  });
}

Expected<std::optional<OnsetRecord>> read_onset(Database& db, std::int64_t trial_id) {
  return guarded(db, [&]() -> Expected<std::optional<OnsetRecord>> {
    Statement s(db.connection(), "SELECT event_id, detail FROM events WHERE trial_id = ?1 AND kind = ?2 "
                                 "ORDER BY event_id DESC LIMIT 1");
    s.bind(1, trial_id).bind_static(2, to_string(EventKind::onset));
    if (!s.step()) return std::optional<OnsetRecord>{};
    OnsetRecord o;
    o.event_id = s.column_int(0);
    auto onset = parse_onset(s.column_text(1));
    if (!onset)
      return corrupt(db, "the onset event " + std::to_string(o.event_id) +
                             " lacks frame_index, head_pose or stick_pose (16 numbers each)");
    o.frame_index = onset->frame_index;
    o.head_pose = onset->head_pose;
    o.stick_pose = onset->stick_pose;
    o.predicted_display_ns = onset->predicted_display_ns;
    o.attempt = onset->attempt;
    return std::optional<OnsetRecord>{o};
  });
}

Expected<std::optional<double>> read_staircase_intensity(Database& db, std::int64_t trial_id) {
  return guarded(db, [&]() -> Expected<std::optional<double>> {
    Statement s(db.connection(), "SELECT intensity FROM staircase_steps WHERE trial_id = ?1");
    s.bind(1, trial_id);
    if (!s.step()) return std::optional<double>{};
    return std::optional<double>{s.column_double(0)};
  });
}

Expected<std::optional<double>> read_adjustment_at(Database& db, std::int64_t trial_id,
                                                   std::int64_t onset_event_id, std::int64_t frame_index) {
  return guarded(db, [&]() -> Expected<std::optional<double>> {
    Statement s(db.connection(),
                "SELECT json_extract(detail, '$.value') FROM events WHERE trial_id = ?1 AND kind = ?4 "
                "AND event_id > ?2 AND event_id < COALESCE((SELECT MIN(event_id) FROM events "
                "WHERE trial_id = ?1 AND kind = ?5 AND event_id > ?2), 9223372036854775807) "
                "AND json_extract(detail, '$.frame_index') <= ?3 ORDER BY event_id DESC LIMIT 1");
    s.bind(1, trial_id).bind(2, onset_event_id).bind(3, frame_index);
    s.bind_static(4, to_string(EventKind::adjustment)).bind_static(5, to_string(EventKind::onset));
    if (!s.step() || s.is_null(0)) return std::optional<double>{};
    return std::optional<double>{s.column_double(0)};
  });
}

Expected<std::optional<HeadAtFrame>> read_head_at_frame(Database& db, std::int64_t session_id,
                                                        std::int64_t frame_index) {
  return guarded(db, [&]() -> Expected<std::optional<HeadAtFrame>> {
    Statement s(db.connection(), "SELECT virtual_pose, t_ns, trial_id FROM tracking_samples WHERE session_id = ?1 "
                                 "AND frame_index = ?2 AND device = 'head' AND virtual_pose IS NOT NULL "
                                 "ORDER BY sample_id DESC LIMIT 1");
    s.bind(1, session_id).bind(2, frame_index);
    if (!s.step()) return std::optional<HeadAtFrame>{};
    HeadAtFrame h;
    const auto blob = s.column_blob(0);
    if (!read_doubles(blob, h.virtual_pose))
      return corrupt(db, "the head pose of frame " + std::to_string(frame_index) + " is " +
                             std::to_string(blob.size()) + " bytes, not 128 (16 doubles)");
    h.t_ns = s.column_int(1);
    h.trial_id = s.column_opt_int(2);
    return std::optional<HeadAtFrame>{h};
  });
}

Expected<std::optional<FrameSpan>> read_trial_frame_span(Database& db, std::int64_t trial_id) {
  return guarded(db, [&]() -> Expected<std::optional<FrameSpan>> {
    Statement s(db.connection(), "SELECT MIN(frame_index), MAX(frame_index) FROM tracking_samples "
                                 "WHERE trial_id = ?1 AND device = 'head'");
    s.bind(1, trial_id);
    if (!s.step() || s.is_null(0)) return std::optional<FrameSpan>{};
    return std::optional<FrameSpan>{FrameSpan{s.column_int(0), s.column_int(1)}};
  });
}

Expected<std::int64_t> read_trial_event_count(Database& db, std::int64_t trial_id, EventKind kind) {
  return guarded(db, [&]() -> Expected<std::int64_t> {
    Statement s(db.connection(), "SELECT COUNT(*) FROM events WHERE trial_id = ?1 AND kind = ?2");
    s.bind(1, trial_id).bind_static(2, to_string(kind));
    s.step();
    return s.column_int(0);
  });
}

Expected<std::optional<ViewGeometry>> read_view_geometry(Database& db, std::int64_t session_id,
                                                         std::int64_t frame_index) {
  return guarded(db, [&]() -> Expected<std::optional<ViewGeometry>> {
    Statement s(db.connection(), "SELECT frame_index, eye_width_px, eye_height_px, eye_views FROM frames "
                                 "WHERE session_id = ?1 AND frame_index <= ?2 AND eye_views IS NOT NULL "
                                 "ORDER BY frame_index DESC LIMIT 1");
    s.bind(1, session_id).bind(2, frame_index);
    if (!s.step()) return std::optional<ViewGeometry>{};
    const std::string where = "the eye geometry of frame " + std::to_string(s.column_int(0));
    const auto w = s.column_opt_int(1), h = s.column_opt_int(2);
    if (!w || !h || *w <= 0 || *h <= 0) return corrupt(db, where + " has no eye image size");
    std::array<double, eye_views_doubles> packed{};
    const auto blob = s.column_blob(3);
    if (!read_doubles(blob, packed))
      return corrupt(db, where + " is " + std::to_string(blob.size()) + " bytes, not 256 (32 doubles)");
    ViewGeometry g;
    g.width_px = static_cast<std::uint32_t>(*w);
    g.height_px = static_cast<std::uint32_t>(*h);
    decode_eye_views(packed, g);
    return std::optional<ViewGeometry>{g};
  });
}

}  // namespace curvlab::harness::data
