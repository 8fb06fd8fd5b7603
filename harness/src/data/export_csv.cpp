// Wide trial CSV: one row per trial, header row, NA for missing values (read
// as missing by both R's read.csv and pandas.read_csv).
#include "export_common.hpp"

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

Expected<ExportSummary> export_trials_csv(Database& db, const ExportOptions& options) {
  auto sessions = load_sessions(db, options);
  if (!sessions) return sessions.error();
  auto table = load_trial_table(db, options);
  if (!table) return table.error();
  const std::string name = "trials.csv";
  auto written = write_staged(options.out_dir, name, false, [&](const std::string& path) -> Expected<ExportSummary> {
    const CsvText csv = render_csv(table.value(), std::nullopt);
    if (auto e = write_text(path, csv.text)) return *e;
    return ExportSummary{{name}, csv.rows};
  });
  if (!written) return written;
  // Play blocks' shots beside the trials, where any were played.
  auto shots = load_shot_table(db, options);
  if (!shots) return shots.error();
  if (shots->rows.empty()) return written;
  auto more = write_staged(options.out_dir, "shots.csv", false, [&](const std::string& path) -> Expected<ExportSummary> {
    const CsvText csv = render_csv(shots.value(), std::nullopt);
    if (auto e = write_text(path, csv.text)) return *e;
    return ExportSummary{{"shots.csv"}, csv.rows};
  });
  if (!more) return more;
  written->files.push_back("shots.csv");
  return written;
}

}  // namespace curvlab::harness::data
