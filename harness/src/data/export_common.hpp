// Shared pieces of the exporters (private to curvlab_data).
#pragma once

#include "curvlab/harness/data/export.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::data::exporting {

struct Column {
  std::string name;
  std::string description;
  std::string unit;  // empty: dimensionless or text
};

using Cell = std::optional<std::string>;  // nullopt: missing

struct SessionInfo {
  std::int64_t session_id = 0;
  std::int64_t session_number = 0;
  std::string pseudonym;
  std::string protocol_name;
  std::string protocol_sha256;
  std::string software_version;
  std::string started_utc;
  std::optional<double> ipd_m;
  std::string dominant_eye;
  std::string session_uuid;
};

struct TrialTable {
  std::vector<Column> columns;
  std::vector<std::vector<Cell>> rows;
  std::vector<std::int64_t> row_session;  // session id of each row
};

// Sessions selected by the options; not_found when --session names none.
Expected<std::vector<SessionInfo>> load_sessions(Database& db, const ExportOptions& options);
Expected<TrialTable> load_trial_table(Database& db, const ExportOptions& options);
// The play blocks' shots, one row per shot (export_shots.cpp); no rows where
// nothing was played.
Expected<TrialTable> load_shot_table(Database& db, const ExportOptions& options);
// partner.csv: a shared game's partner head as drawn, with the players' distance.
Expected<TrialTable> load_partner_table(Database& db, const ExportOptions& options);
// The questionnaire blocks' answers, one row per item answered, and their
// scores, one row per block and subscale (export_questionnaires.cpp); no
// rows where no questionnaire was answered.
// The session, participant and block of a row of a table aliased `x` that
// has session_id and trial_id (s, p, t and b in the query).
inline constexpr const char* kBlockJoins =
    "JOIN sessions s ON s.session_id = x.session_id "
    "JOIN participants p ON p.participant_id = s.participant_id "
    "JOIN trials t ON t.trial_id = x.trial_id JOIN blocks b ON b.block_id = t.block_id ";
// Column `x.<column>` (ns on the session clock) in seconds from the session's
// first frame.
inline std::string seconds_from_start(const std::string& column) {
  return "(x." + column + " - (SELECT MIN(t_ns) FROM frames f WHERE f.session_id = x.session_id)) / 1e9";
}
// The rows of `sql` (session id first, then one column per table column),
// `session_id` bound to ?1 (NULL: every session).
Expected<TrialTable> load_rows(Database& db, const ExportOptions& options, std::vector<Column> columns,
                               const std::string& sql);
Expected<TrialTable> load_questionnaire_table(Database& db, const ExportOptions& options);
Expected<TrialTable> load_questionnaire_score_table(Database& db, const ExportOptions& options);

// What messages call the exported data: the options' source, else the file.
std::string origin(const Database& db, const ExportOptions& options);
// The labels check of check_export_labels on sessions already loaded.
std::optional<DataError> check_labels(const std::vector<SessionInfo>& sessions, const std::string& source);

// The trial table as CSV (export_csv.cpp), all rows or one session's, and
// the number of rows written.
struct CsvText {
  std::string text;
  std::size_t rows = 0;
};
CsvText render_csv(const TrialTable& table, std::optional<std::int64_t> only_session);

// Writes one format's part of the out folder (`name`: trials.csv, psychds or
// bids) under a temporary name beside it, out_dir/NAME.partial-PID (a
// folder when `folder`), and puts it in place only when `write` succeeded:
// a complete export replaces out_dir/NAME whole; a failed one (a full
// disk…) removes its temporary copy and leaves out_dir/NAME as it was, and
// removes out_dir when it made it and nothing else is in it. Leftovers of
// killed exports are removed first. `write` is given the temporary path.
Expected<ExportSummary> write_staged(const std::string& out_dir, const std::string& name, bool folder,
                                     const std::function<Expected<ExportSummary>(const std::string& path)>& write);

// Creates the folder (and parents); io error naming it on failure.
std::optional<DataError> make_dir(const std::string& dir);
// Writes the whole file or returns an io error naming it.
std::optional<DataError> write_text(const std::string& path, const std::string& text);

std::string csv_field(const std::string& value);  // RFC 4180 quoting when needed
std::string tsv_field(const std::string& value);  // tabs and newlines become spaces
// Letters and digits only (BIDS labels, Psych-DS keyword values).
std::string alnum_label(const std::string& text);

}  // namespace curvlab::harness::data::exporting
