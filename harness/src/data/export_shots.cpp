// The play blocks' shots as a table (shots.csv; a Psych-DS file per session
// that played): one row per shot, with the session, participant, block and
// the shot's inputs and outcome. Events and ball positions stay in the
// database's JSON columns (docs/billiards.md). A shared game's partner as
// drawn, head rows with the players' distance (partner.csv).
#include "export_common.hpp"

namespace curvlab::harness::data::exporting {

Expected<TrialTable> load_shot_table(Database& db, const ExportOptions& options) {
  std::vector<Column> columns{
      {"session_uuid", "The session's UUID", ""},
      {"participant", "The participant's pseudonym", ""},
      {"session_number", "The participant's session number", ""},
      {"block", "The play block's name", ""},
      {"space", "The space of the table: S3, E3 or H3", ""},
      {"shot_index", "0-based shot number in the block", ""},
      {"t_s", "Time of the strike from the session's start", "s"},
      {"rest_s", "Time the balls came to rest from the session's start", "s"},
      {"player", "Who shot: participant or simulated", ""},
      {"ball", "The struck ball", ""},
      {"aim_x", "Aim, x component of a unit vector in the struck ball's frame", ""},
      {"aim_z", "Aim, z component of a unit vector in the struck ball's frame", ""},
      {"speed_m_s", "The ball's speed after the strike", "m/s"},
      {"cue_speed_m_s", "The cue's speed at the strike", "m/s"},
      {"tip_side", "Tip offset to the right of the ball's centre, fraction of its radius", ""},
      {"tip_height", "Tip offset above the ball's centre, fraction of its radius", ""},
      {"miscue", "The tip slipped off the ball (TRUE/FALSE)", ""},
      {"events", "Number of events the shot caused", ""},
      {"pocketed", "Object balls the shot pocketed (ids separated by spaces)", ""},
      {"pocketed_count", "Number of object balls the shot pocketed", ""},
  };
  return load_rows(db, options, std::move(columns),
                   "SELECT x.session_id, s.session_uuid, p.pseudonym, s.session_number, b.name, "
                   "json_extract(x.table_settings, '$.space'), x.shot_index, " +
                       seconds_from_start("t_ns") + ", " + seconds_from_start("rest_ns") +
                       ", x.player, x.ball, x.aim_x, x.aim_z, x.speed_m_s, x.cue_speed_m_s, x.tip_side, "
                       "x.tip_height, CASE x.miscue WHEN 1 THEN 'TRUE' ELSE 'FALSE' END, x.event_count, "
                       "(SELECT group_concat(value, ' ') FROM json_each(x.pocketed)), json_array_length(x.pocketed) "
                       "FROM shots x " +
                       kBlockJoins +
                       "WHERE ?1 IS NULL OR x.session_id = ?1 ORDER BY s.session_uuid, x.session_id, x.trial_id, "
                       "x.shot_index");
}

Expected<TrialTable> load_partner_table(Database& db, const ExportOptions& options) {
  std::vector<Column> columns{
      {"session_uuid", "This station's session UUID", ""},
      {"participant", "This station's participant (pseudonym)", ""},
      {"session_number", "The participant's session number", ""},
      {"block", "The shared play block's name", ""},
      {"frame_index", "This station's frame that drew the partner", ""},
      {"t_s", "When the frame was shown, from the session's start", "s"},
      {"distance_m", "Geodesic distance in the virtual space between the two players' heads", "m"},
      {"tracked", "The partner's station tracked its head (TRUE/FALSE)", ""},
      {"extrapolated", "Drawn past the newest pose received (TRUE/FALSE)", ""},
      {"sample_age_ms", "Age of the newest pose received when the frame was shown", "ms"},
  };
  return load_rows(db, options, std::move(columns),
                   "SELECT x.session_id, s.session_uuid, p.pseudonym, s.session_number, b.name, x.frame_index, " +
                       seconds_from_start("t_ns") +
                       ", x.distance_m, CASE x.tracked WHEN 1 THEN 'TRUE' ELSE 'FALSE' END, "
                       "CASE x.extrapolated WHEN 1 THEN 'TRUE' ELSE 'FALSE' END, x.sample_age_ns / 1e6 "
                       "FROM partner_samples x " +
                       kBlockJoins +
                       "WHERE x.device = 'head' AND (?1 IS NULL OR x.session_id = ?1) "
                       "ORDER BY s.session_uuid, x.session_id, x.sample_id");
}

}  // namespace curvlab::harness::data::exporting
