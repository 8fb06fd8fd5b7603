// Wide trial CSV: one row per trial, header row, NA for missing values (read
// as missing by both R's read.csv and pandas.read_csv); beside it, where
// the sessions recorded other instruments' Lab Streaming Layer streams,
// lsl_samples.csv: one row per recorded sample (docs/lsl.md).
#include "export_common.hpp"

#include "curvlab/harness/data/sqlite.hpp"

namespace curvlab::harness::data {

using namespace exporting;

namespace exporting {
CsvText render_csv(const TrialTable& table, std::optional<std::int64_t> only_session) {
  CsvText csv;
  std::string& out = csv.text;
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    if (c) out += ',';
    out += csv_field(table.columns[c].name);
  }
  out += "\r\n";
  for (std::size_t r = 0; r < table.rows.size(); ++r) {
    if (only_session && table.row_session[r] != *only_session) continue;
    const auto& row = table.rows[r];
    for (std::size_t c = 0; c < row.size(); ++c) {
      if (c) out += ',';
      out += row[c] ? csv_field(*row[c]) : std::string("NA");
    }
    out += "\r\n";
    ++csv.rows;
  }
  return csv;
}
}  // namespace exporting

namespace {

// The recorded samples of the exported sessions, with their streams; no
// rows when none recorded any.
Expected<CsvText> lsl_samples_csv(Database& db, const ExportOptions& options) {
  try {
    Statement s(db.connection(),
                "SELECT st.session_id, st.name, st.type, st.source_id, s.t_ns, s.lsl_time_s, s.lsl_offset_s, "
                "s.received_ns, s.value FROM lsl_samples s JOIN lsl_streams st USING (lsl_stream_id) "
                "WHERE st.role = 'recorded' AND (?1 IS NULL OR st.session_id = ?1) "
                "ORDER BY st.session_id, s.lsl_stream_id, s.lsl_sample_id");
    s.bind(1, options.session_id);
    CsvText csv;
    csv.text = "session_id,stream_name,stream_type,source_id,t_ns,lsl_time_s,lsl_offset_s,received_ns,value\r\n";
    while (s.step()) {
      for (int c = 0; c < 9; ++c) {
        if (c > 0) csv.text += ',';
        csv.text += csv_field(s.column_text(c));
      }
      csv.text += "\r\n";
      ++csv.rows;
    }
    return csv;
  } catch (const SqliteFailure& failure) {
    return to_data_error(failure, db.path());
  }
}

}  // namespace

Expected<ExportSummary> export_trials_csv(Database& db, const ExportOptions& options) {
  auto sessions = load_sessions(db, options);
  if (!sessions) return sessions.error();
  auto table = load_trial_table(db, options);
  if (!table) return table.error();
  auto recorded = lsl_samples_csv(db, options);
  if (!recorded) return recorded.error();
  const std::string name = "trials.csv";
  auto written = write_staged(options.out_dir, name, false, [&](const std::string& path) -> Expected<ExportSummary> {
    const CsvText csv = render_csv(table.value(), std::nullopt);
    if (auto e = write_text(path, csv.text)) return *e;
    return ExportSummary{{name}, csv.rows};
  });
  if (!written) return written;
  if (recorded->rows > 0) {
    const std::string lsl_name = "lsl_samples.csv";
    auto lsl = write_staged(options.out_dir, lsl_name, false, [&](const std::string& path) -> Expected<ExportSummary> {
      if (auto e = write_text(path, recorded->text)) return *e;
      return ExportSummary{{lsl_name}, recorded->rows};
    });
    if (!lsl) return lsl.error();
    written->files.push_back(lsl_name);
  }
  // Play blocks' shots, questionnaire blocks' answers and scores, and a
  // shared game's partner beside the trials, where there are any.
  auto shots = load_shot_table(db, options);
  if (!shots) return shots.error();
  auto answers = load_questionnaire_table(db, options);
  if (!answers) return answers.error();
  auto scores = load_questionnaire_score_table(db, options);
  if (!scores) return scores.error();
  auto partner = load_partner_table(db, options);
  if (!partner) return partner.error();
  const std::pair<const char*, const TrialTable*> beside[] = {
      {"shots.csv", &shots.value()}, {"questionnaires.csv", &answers.value()},
      {"questionnaire_scores.csv", &scores.value()}, {"partner.csv", &partner.value()}};
  for (const auto& [file, rows] : beside) {
    if (rows->rows.empty()) continue;
    const std::string file_name(file);
    auto more = write_staged(options.out_dir, file_name, false, [&](const std::string& path) -> Expected<ExportSummary> {
      const CsvText csv = render_csv(*rows, std::nullopt);
      if (auto e = write_text(path, csv.text)) return *e;
      return ExportSummary{{file_name}, csv.rows};
    });
    if (!more) return more;
    written->files.push_back(file_name);
  }
  return written;
}

}  // namespace curvlab::harness::data
