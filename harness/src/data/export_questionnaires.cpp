// The questionnaire blocks' answers and scores as tables
// (docs/questionnaires.md): questionnaires.csv, one row per answered item,
// and questionnaire_scores.csv, one row per session × block × subscale
// (participant, session, block and instrument in every row); a Psych-DS
// file of each per session that answered any.
#include "export_common.hpp"

namespace curvlab::harness::data::exporting {

namespace {

std::vector<Column> block_columns() {
  return {
      {"session_uuid", "The session's UUID", ""},
      {"participant", "The participant's pseudonym", ""},
      {"session_number", "The participant's session number", ""},
      {"block", "The block's name", ""},
      {"block_index", "0-based position of the block in the session's run order", ""},
      {"instrument", "The questionnaire: ssq (Simulator Sickness Questionnaire) or the protocol's instrument name", ""},
  };
}


}  // namespace

Expected<TrialTable> load_questionnaire_table(Database& db, const ExportOptions& options) {
  std::vector<Column> columns = block_columns();
  for (Column c : std::vector<Column>{
           {"item_index", "0-based position of the item in the instrument", ""},
           {"item_id", "The item's id", ""},
           {"item_text", "The item as shown to the participant", ""},
           {"value", "The scale value answered (before any reversal for scoring)", ""},
           {"label", "The label of the scale point answered", ""},
           {"rt_ms", "Time from the item's first frame to the answering input", "ms"},
           {"answered_s", "Time of the answer from the session's start", "s"},
           {"device", "The input that answered: keyboard, script, hid:<name>, xr:<hand> or observer", ""},
       })
    columns.push_back(std::move(c));
  return load_rows(db, options, std::move(columns),
                   std::string("SELECT x.session_id, s.session_uuid, p.pseudonym, s.session_number, b.name, "
                               "b.block_index, x.instrument, x.item_index, x.item_id, x.item_text, x.value, x.label, "
                               "x.rt_ms, ") +
                       seconds_from_start("t_ns") + ", x.device FROM questionnaire_answers x " +
                       kBlockJoins +
                       "WHERE ?1 IS NULL OR x.session_id = ?1 ORDER BY s.session_uuid, x.session_id, "
                       "b.block_index, x.item_index");
}

Expected<TrialTable> load_questionnaire_score_table(Database& db, const ExportOptions& options) {
  std::vector<Column> columns = block_columns();
  for (Column c : std::vector<Column>{
           {"subscale", "The subscale (SSQ: nausea, oculomotor, disorientation, total)", ""},
           {"rule", "How the subscale's items combine: sum or mean", ""},
           {"weight", "The factor the sum or mean is multiplied by (SSQ: 9.54, 7.58, 13.92, 3.74)", ""},
           {"items", "Items the subscale counts (an item counted twice, twice)", ""},
           {"answered", "Of those, items answered", ""},
           {"raw", "Sum or mean of the items' scored values (reversed items mirrored); empty unless all answered", ""},
           {"score", "weight × raw: the subscale's score", ""},
       })
    columns.push_back(std::move(c));
  return load_rows(db, options, std::move(columns),
                   std::string("SELECT x.session_id, s.session_uuid, p.pseudonym, s.session_number, b.name, "
                               "b.block_index, x.instrument, x.subscale, x.rule, x.weight, x.items, x.answered, "
                               "x.raw, x.score FROM questionnaire_scores x ") +
                       kBlockJoins +
                       "WHERE ?1 IS NULL OR x.session_id = ?1 ORDER BY s.session_uuid, x.session_id, "
                       "b.block_index, x.subscale_index");
}

}  // namespace curvlab::harness::data::exporting
