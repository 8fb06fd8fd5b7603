#include "export_common.hpp"

#include "curvlab/harness/data/events.hpp"
#include "curvlab/harness/data/session_list.hpp"
#include "curvlab/harness/data/sqlite.hpp"
#include "curvlab/harness/data/staging.hpp"
#include "curvlab/harness/platform/files.hpp"
#include "curvlab/harness/platform/process.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <system_error>

namespace curvlab::harness::data::exporting {

namespace fs = std::filesystem;

std::optional<DataError> make_dir(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    return DataError{DataError::Kind::io, "cannot create output folder " + dir + ": " +
                                              (ec ? ec.message() : "not a folder")};
  return std::nullopt;
}

namespace {

// A staged file or folder, removed unless it was put in place, with the out
// folder when the export made it and left it empty. Owned by one export.
class StagedPath {
 public:
  StagedPath(fs::path path, fs::path out_dir, bool made_out_dir)
      : path_(std::move(path)), out_dir_(std::move(out_dir)), made_out_dir_(made_out_dir) {}
  ~StagedPath() {
    if (kept_) return;
    std::error_code ec;
    fs::remove_all(path_, ec);
    if (made_out_dir_) fs::remove(out_dir_, ec);  // only when empty
  }
  StagedPath(const StagedPath&) = delete;
  StagedPath& operator=(const StagedPath&) = delete;
  const fs::path& path() const { return path_; }
  void keep() { kept_ = true; }

 private:
  fs::path path_, out_dir_;
  bool made_out_dir_ = false;
  bool kept_ = false;
};

// Puts `staged` where `target` is: rename(2) replaces a file, or a folder
// with a missing or empty one, in one step; a folder with content is
// exchanged with it in one step (renameat2 RENAME_EXCHANGE) and the old one
// removed, or, on a file system that cannot exchange, moved `aside` first.
std::optional<DataError> put_in_place(const fs::path& staged, const fs::path& target, const fs::path& aside) {
  std::error_code ec;
  int err = platform::rename_replacing(staged.string(), target.string());
  if (err == 0) return std::nullopt;
  if (err == ENOTEMPTY || err == EEXIST) {
    err = platform::exchange_paths(staged.string(), target.string());
    if (err == 0) {
      fs::remove_all(staged, ec);  // the old content, now under the staged name
      return std::nullopt;
    }
    if ((err == EINVAL || err == ENOSYS) && platform::rename_replacing(target.string(), aside.string()) == 0) {
      err = platform::rename_replacing(staged.string(), target.string());
      if (err == 0) {
        fs::remove_all(aside, ec);
        return std::nullopt;
      }
      (void)platform::rename_replacing(aside.string(), target.string());
    }
  }
  return DataError{DataError::Kind::io, "cannot put " + staged.string() + " in place of " + target.string() + ": " +
                                            std::generic_category().message(err)};
}

}  // namespace

Expected<ExportSummary> write_staged(const std::string& out_dir, const std::string& name, bool folder,
                                     const std::function<Expected<ExportSummary>(const std::string& path)>& write) {
  std::error_code ec;
  const bool out_existed = fs::exists(out_dir, ec);
  if (auto e = make_dir(out_dir)) return *e;
  for (const char* kind : {".partial-", ".replaced-"}) remove_stale_staging(out_dir, name + kind, folder ? StagingKind::folder : StagingKind::file);
  const std::string pid = std::to_string(platform::process_id());
  const fs::path target = fs::path(out_dir) / name;
  const bool target_existed = fs::exists(fs::symlink_status(target, ec));
  StagedPath staged(fs::path(out_dir) / (name + ".partial-" + pid), out_dir, !out_existed);
  auto failed = [&](DataError e) {
    e.message += "; " + target.string() + (target_existed ? " was left as it was" : " was not written");
    return e;
  };
  fs::remove_all(staged.path(), ec);
  if (folder)
    if (auto e = make_dir(staged.path().string())) return failed(*e);
  auto written = write(staged.path().string());
  if (!written) return failed(written.error());
  if (auto e = put_in_place(staged.path(), target, fs::path(out_dir) / (name + ".replaced-" + pid)))
    return failed(*e);
  staged.keep();
  return written;
}

std::optional<DataError> write_text(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return DataError{DataError::Kind::io, "cannot write " + path};
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return DataError{DataError::Kind::io, "writing " + path + " failed (disk full?)"};
  return std::nullopt;
}

std::string csv_field(const std::string& v) {
  if (v.find_first_of(",\"\r\n") == std::string::npos) return v;
  std::string out = "\"";
  for (char c : v) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string tsv_field(const std::string& v) {
  std::string out = v;
  for (char& c : out)
    if (c == '\t' || c == '\n' || c == '\r') c = ' ';
  return out;
}

std::string alnum_label(const std::string& text) {
  std::string out;
  for (char c : text)
    if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) out += c;
  return out.empty() ? "unnamed" : out;
}

namespace {

// The first group of distinct `names` (pseudonyms or protocol names, in
// order of first appearance) whose labels are equal ignoring case.
std::optional<DataError> label_clash(const std::vector<std::string>& names, const std::string& what,
                                     const std::string& source) {
  std::map<std::string, std::vector<std::string>> by_label;  // lower-case label → names
  for (const auto& name : names) {
    std::string key = alnum_label(name);
    for (char& c : key) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    auto& group = by_label[key];
    if (std::find(group.begin(), group.end(), name) == group.end()) group.push_back(name);
  }
  for (const auto& [key, group] : by_label) {
    if (group.size() < 2) continue;
    std::string listed;
    std::vector<std::string> labels;
    for (std::size_t i = 0; i < group.size(); ++i) {
      listed += (i == 0 ? "" : i + 1 == group.size() ? " and " : ", ") + ("\"" + group[i] + "\"");
      const std::string label = alnum_label(group[i]);
      if (std::find(labels.begin(), labels.end(), label) == labels.end()) labels.push_back(label);
    }
    std::string shared = "would share the label \"" + labels.front() + "\"";
    if (labels.size() > 1) {
      shared = "would get the labels";
      for (std::size_t i = 0; i < labels.size(); ++i) shared += (i == 0 ? " \"" : ", \"") + labels[i] + "\"";
      shared += ", which name one file on a disk that ignores case";
    }
    return DataError{DataError::Kind::bad_input,
                     source + ": " + what + " " + listed + " " + shared +
                         " in exported file names (labels keep letters and digits only), so one's files would "
                         "overwrite another's; nothing was written. Export their sessions one at a time "
                         "(--session), or the trial CSV alone (--format csv), which names no file after them"};
  }
  return std::nullopt;
}

}  // namespace

std::string origin(const Database& db, const ExportOptions& options) {
  return options.source.empty() ? db.path() : options.source;
}

std::optional<DataError> check_labels(const std::vector<SessionInfo>& sessions, const std::string& source) {
  std::vector<std::string> pseudonyms, protocols;
  for (const auto& s : sessions) {
    pseudonyms.push_back(s.pseudonym);
    protocols.push_back(s.protocol_name);
  }
  if (auto e = label_clash(pseudonyms, "participants", source)) return e;
  return label_clash(protocols, "protocols", source);
}

Expected<std::vector<SessionInfo>> load_sessions(Database& db, const ExportOptions& options) {
  try {
    Statement s(db.connection(),
                "SELECT s.session_id, s.session_number, p.pseudonym, pr.name, pr.sha256, "
                "s.software_version, s.started_utc, p.ipd_m, p.dominant_eye, s.session_uuid FROM sessions s "
                "JOIN participants p ON p.participant_id = s.participant_id "
                "JOIN protocols pr ON pr.protocol_id = s.protocol_id "
                "WHERE ?1 IS NULL OR s.session_id = ?1 ORDER BY s.session_uuid, s.session_id");
    s.bind(1, options.session_id);
    std::vector<SessionInfo> out;
    while (s.step()) {
      SessionInfo info;
      info.session_id = s.column_int(0);
      info.session_number = s.column_int(1);
      info.pseudonym = s.column_text(2);
      info.protocol_name = s.column_text(3);
      info.protocol_sha256 = s.column_text(4);
      info.software_version = s.column_text(5);
      info.started_utc = s.column_text(6);
      info.ipd_m = s.column_opt_double(7);
      info.dominant_eye = s.column_text(8);
      info.session_uuid = s.column_opt_text(9).value_or("");
      out.push_back(std::move(info));
    }
    if (out.empty() && options.session_id) return missing_session_error(db, *options.session_id);
    return out;
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db.path());
  }
}

namespace {

Cell json_cell(const nlohmann::ordered_json& v) {
  if (v.is_null()) return std::nullopt;
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return std::string(v.get<bool>() ? "TRUE" : "FALSE");
  return v.dump();
}

}  // namespace

namespace {

// The trial export's fixed columns: name, description and unit beside the
// SQL that reads them, so a column and its description cannot drift apart.
struct FixedColumn {
  const char* name;
  const char* description;
  const char* unit;
  const char* sql;
};

// Who, which session and protocol, where in the session.
std::vector<FixedColumn> identity_columns() {
  return {
    {"session_id", "Database id of the session (local to the file; session_uuid identifies it across files)", "",
     "t.session_id"},
    {"session_uuid", "The session's identity across files and machines (RFC 9562 UUID)", "",
     "se.session_uuid"},
    {"participant", "Participant pseudonym (no identifying data)", "",
     "p.pseudonym"},
    {"session_number", "Session number of this participant, from 1", "",
     "se.session_number"},
    {"protocol_sha256", "SHA-256 of the protocol text the session ran", "",
     "pr.sha256"},
    {"block_index", "Block position in the session, from 0", "",
     "b.block_index"},
    {"block_name", "Block name from the protocol", "",
     "b.name"},
    {"is_practice", "1 for practice blocks, 0 otherwise", "",
     "b.is_practice"},
    {"trial_index", "Trial position in the session, from 0", "",
     "t.trial_index"},
    {"trial_in_block", "Trial position in its block, from 0", "",
     "t.trial_in_block"},
  };
}

// How the trial ended and what was answered, when.
std::vector<FixedColumn> outcome_columns() {
  return {
    {"status", "pending, running, completed, skipped or aborted", "",
     "t.status"},
    {"end_reason",
       "Skipped or aborted trials: why (staircase_finished, psi_finished, operator, tracking_lost, pause, "
       "recenter, quit); empty otherwise",
       "",
     "t.end_reason"},
    {"attempt", "How many times the trial was started (more than 1 after a resume)", "",
     "t.attempt"},
    {"onset_ns", "Stimulus onset on the session's monotonic clock", "ns",
     "t.onset_ns"},
    {"response_ns", "Response time stamp on the session's monotonic clock", "ns",
     "t.response_ns"},
    {"rt_ns", "Response time: response_ns minus onset_ns", "ns",
     "t.rt_ns"},
    {"response", "The participant's response", "",
     "t.response"},
    {"response_device", "Device that gave the response", "",
     "t.response_device"},
    {"completed_utc", "Wall-clock time the trial was committed (UTC, ISO 8601)", "",
     "t.completed_utc"},
  };
}

// Staircase steps and the psi method's posterior after each answer.
std::vector<FixedColumn> adaptive_columns() {
  return {
    {"staircase", "Staircase trials: the staircase (block:name) the trial stepped", "",
     "st.staircase"},
    {"staircase_step", "Staircase trials: the step's index in its staircase, from 0", "",
     "st.step_index"},
    {"intensity", "Staircase trials: the value of the staircase's parameter shown", "protocol unit",
     "st.intensity"},
    {"is_reversal", "Staircase trials: 1 when the response reversed the staircase's direction", "",
     "st.is_reversal"},
    {"pse_mean",
       "Bayesian adaptive (psi) trials: posterior mean of the PSE alpha of P(positive | x) = lapse/2 + "
       "(1 - lapse) Phi(slope (x - alpha)) after this trial's answer",
       "protocol unit",
     "json_extract(po.detail, '$.pse_mean')"},
    {"pse_sd", "Bayesian adaptive (psi) trials: posterior SD of the PSE after this trial's answer", "protocol unit",
     "json_extract(po.detail, '$.pse_sd')"},
    {"slope_mean", "Bayesian adaptive (psi) trials: posterior mean of the slope after this trial's answer",
     "1/protocol unit",
     "json_extract(po.detail, '$.slope_mean')"},
    {"slope_sd", "Bayesian adaptive (psi) trials: posterior SD of the slope after this trial's answer",
     "1/protocol unit",
     "json_extract(po.detail, '$.slope_sd')"},
    {"lapse_mean",
       "Bayesian adaptive (psi) trials that estimate the lapse rate: its posterior mean after this trial's answer; "
       "empty when the lapse rate is fixed",
       "",
     "json_extract(po.detail, '$.lapse_mean')"},
    {"lapse_sd",
       "Bayesian adaptive (psi) trials that estimate the lapse rate: its posterior SD after this trial's answer",
       "",
     "json_extract(po.detail, '$.lapse_sd')"},
    {"posterior_entropy",
       "Bayesian adaptive (psi) trials: entropy of the joint posterior over the grid after this trial's answer",
       "nat",
     "json_extract(po.detail, '$.entropy_nats')"},
  };
}

// Lost tracking and late frames during the trial.
std::vector<FixedColumn> frame_columns() {
  return {
    {"tracking_lost_ms",
       "Trials completed with tracking lost (tracking.on_loss = \"flag\"): how long the head was "
       "untracked, in spells longer than tracking.loss_ms",
       "ms",
     "tf.lost_ms"},
    {"frames_late",
       "Frames of the trial (all attempts) the runtime reported late: the display time skipped a refresh "
       "or the frame was not to be rendered (frames.late)",
       "",
     "COALESCE(fl.late, 0)"},
    {"onset_late",
       "1 when the stimulus onset frame was late (not shown at its predicted display time), 0 when on "
       "time; empty without an onset",
       "",
     "CASE WHEN t.onset_ns IS NULL THEN NULL ELSE COALESCE(fl.onset_late, 0) END"},
  };
}

// The model's vergence demand and, with eye tracking, the measured gaze.
std::vector<FixedColumn> gaze_columns() {
  return {
    {"vergence_demand_arcmin",
       "The vergence the fixated point of the stimulus demands of the eyes, by the human perception model "
       "(the onset's percept; positive converging, negative diverging beyond parallel); empty where the "
       "session stored no percept (no simulated observer)",
       "arcmin",
     "json_extract(op.detail, '$.percept.vergence_demand_arcmin')"},
    {"gaze_samples",
       "Sessions with eye tracking: gaze samples (one per frame) during the stimulus, from its onset for "
       "timeline.stimulus_ms; empty without eye tracking",
       "",
     "CASE WHEN gs.session_id IS NULL THEN NULL ELSE COALESCE(gz.n, 0) END"},
    {"gaze_valid_samples",
       "Sessions with eye tracking: of gaze_samples, those with both eyes' gaze valid (per-eye gaze), or the "
       "combined gaze valid where only that is tracked; empty without eye tracking",
       "",
     "CASE WHEN gs.session_id IS NULL THEN NULL ELSE COALESCE(gz.valid, 0) END"},
    {"gaze_vergence_arcmin",
       "Sessions with per-eye gaze: mean measured vergence of the eyes during the stimulus (positive "
       "converging, negative diverging beyond parallel), over the samples with both eyes valid; compare "
       "vergence_demand_arcmin; empty without per-eye gaze or without a valid sample",
       "arcmin",
     "gz.vergence_rad * 10800.0 / 3.141592653589793"},
  };
}

const std::vector<FixedColumn>& fixed_columns() {
  static const std::vector<FixedColumn> columns = [] {
    std::vector<FixedColumn> all;
    for (auto part : {identity_columns, outcome_columns, adaptive_columns, frame_columns, gaze_columns}) {
      auto more = part();
      all.insert(all.end(), more.begin(), more.end());
    }
    return all;
  }();
  return columns;
}

// The fixed columns, then the conditions and stimulus JSON texts.
std::string trial_select() {
  std::string sql = "SELECT ";
  for (const auto& c : fixed_columns()) sql += std::string(c.sql) + ", ";
  return sql +
         "t.conditions, t.stimulus FROM trials t "
         "LEFT JOIN staircase_steps st ON st.trial_id = t.trial_id "
         // One pass over the events, not one per trial.
         "LEFT JOIN (SELECT trial_id, SUM(json_extract(detail, '$.lost_ms')) AS lost_ms "
         "FROM events WHERE kind = ?2 GROUP BY trial_id) tf "
         "ON tf.trial_id = t.trial_id "
         // A psi trial's posterior: at most one event per trial (written with its step).
         "LEFT JOIN (SELECT trial_id, detail FROM events WHERE kind = ?3) po ON po.trial_id = t.trial_id "
         // One pass over the frames: the trial's late frames, and whether its
         // onset frame (displayed at onset_ns) was one of them.
         "LEFT JOIN (SELECT f.trial_id, SUM(f.late) AS late, "
         "MAX(f.late = 1 AND f.predicted_display_ns = ot.onset_ns) AS onset_late FROM frames f "
         "JOIN trials ot ON ot.trial_id = f.trial_id GROUP BY f.trial_id) fl ON fl.trial_id = t.trial_id "
         // Gaze during the stimulus: from the onset (the completed attempt's)
         // for the stimulus_ms its onset event recorded, else up to the
         // response. Sessions with gaze at all, so that a trial without
         // samples reads 0 there and empty where no eye was tracked.
         // The onset of the attempt the trial's onset_ns comes from.
         "LEFT JOIN (SELECT trial_id, detail FROM events WHERE kind = ?4) op ON op.trial_id = t.trial_id "
         "AND json_extract(op.detail, '$.predicted_display_ns') = t.onset_ns "
         "LEFT JOIN (SELECT DISTINCT session_id FROM gaze_samples) gs ON gs.session_id = t.session_id "
         "LEFT JOIN (SELECT g.trial_id, COUNT(*) AS n, "
         "SUM(CASE WHEN g.left_valid IS NOT NULL THEN g.vergence_rad IS NOT NULL ELSE g.combined_valid = 1 END) "
         "AS valid, AVG(g.vergence_rad) AS vergence_rad FROM gaze_samples g "
         "JOIN trials gt ON gt.trial_id = g.trial_id "
         "LEFT JOIN (SELECT trial_id, json_extract(detail, '$.predicted_display_ns') AS at_ns, "
         "json_extract(detail, '$.stimulus_ms') AS ms FROM events WHERE kind = ?4) oe "
         "ON oe.trial_id = gt.trial_id AND oe.at_ns = gt.onset_ns "
         "WHERE g.t_ns >= gt.onset_ns AND g.t_ns < COALESCE(gt.onset_ns + oe.ms * 1000000, gt.response_ns) "
         "GROUP BY g.trial_id) gz ON gz.trial_id = t.trial_id "
         "JOIN sessions se ON se.session_id = t.session_id "
         "JOIN participants p ON p.participant_id = se.participant_id "
         "JOIN protocols pr ON pr.protocol_id = se.protocol_id "
         "JOIN blocks b ON b.block_id = t.block_id "
         "WHERE ?1 IS NULL OR t.session_id = ?1 ORDER BY se.session_uuid, t.session_id, t.trial_index";
}

// The names a JSON column family (conditions or stimulus) uses, in order
// of first appearance, and each row's object.
struct JsonColumns {
  std::vector<std::string> names;
  std::map<std::string, std::size_t> position;
  std::vector<nlohmann::ordered_json> rows;

  void add(const std::string& text) {
    auto obj = nlohmann::ordered_json::parse(text, nullptr, false);
    if (obj.is_object())
      for (auto it = obj.begin(); it != obj.end(); ++it)
        if (position.emplace(it.key(), names.size()).second) names.push_back(it.key());
    rows.push_back(std::move(obj));
  }

  // Columns `prefix`<name>, described as `what` "<name>" `source`.
  void append_to(TrialTable& table, const std::string& prefix, const std::string& what,
                 const std::string& source) const {
    for (const auto& n : names)
      table.columns.push_back({prefix + n, what + " \"" + n + "\" " + source, ""});
    for (std::size_t r = 0; r < table.rows.size(); ++r) {
      const auto& obj = rows[r];
      for (const auto& n : names)
        table.rows[r].push_back(obj.is_object() && obj.contains(n) ? json_cell(obj[n]) : std::nullopt);
    }
  }
};

}  // namespace

Expected<TrialTable> load_trial_table(Database& db, const ExportOptions& options) {
  TrialTable table;
  for (const auto& c : fixed_columns()) table.columns.push_back({c.name, c.description, c.unit});
  const int fixed = static_cast<int>(table.columns.size());
  JsonColumns conditions, stimulus;
  try {
    Statement s(db.connection(), trial_select());
    s.bind(1, options.session_id).bind_static(2, to_string(EventKind::tracking_flagged));
    s.bind_static(3, to_string(EventKind::posterior));
    s.bind_static(4, to_string(EventKind::onset));
    while (s.step()) {
      std::vector<Cell> row;
      for (int c = 0; c < fixed; ++c) row.push_back(s.column_opt_text(c));
      table.rows.push_back(std::move(row));
      table.row_session.push_back(s.column_int(0));
      conditions.add(s.column_text(fixed));
      stimulus.add(s.column_text(fixed + 1));
    }
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db.path());
  }
  conditions.append_to(table, "cond_", "Condition value", "from the protocol");
  stimulus.append_to(table, "stim_", "Stimulus parameter",
                     "as shown: the protocol's value, or the value a staircase or an adjustment set on the trial "
                     "(empty where the trial showed none)");
  return table;
}

// The rows of `sql` (session id first, then one column per table column),
// `session_id` bound to ?1 (NULL: every session).
Expected<TrialTable> load_rows(Database& db, const ExportOptions& options, std::vector<Column> columns,
                               const std::string& sql) {
  TrialTable table;
  table.columns = std::move(columns);
  try {
    Statement s(db.connection(), sql);
    s.bind(1, options.session_id);
    while (s.step()) {
      std::vector<Cell> row;
      for (int c = 1; c <= static_cast<int>(table.columns.size()); ++c) row.push_back(s.column_opt_text(c));
      table.rows.push_back(std::move(row));
      table.row_session.push_back(s.column_int(0));
    }
  } catch (const SqliteFailure& f) {
    return to_data_error(f, db.path());
  }
  return table;
}

}  // namespace curvlab::harness::data::exporting

namespace curvlab::harness::data {

const std::vector<ExportFormat>& export_formats() {
  static const std::vector<ExportFormat> formats{
      {"csv", "csv", false, &export_trials_csv},
      {"psychds", "psychds", true, &export_psychds},
      {"bids-motion", "bids", true, &export_bids_motion},
  };
  return formats;
}

Expected<Done> check_export_labels(Database& db, const ExportOptions& options) {
  auto sessions = exporting::load_sessions(db, options);
  if (!sessions) return sessions.error();
  if (auto e = exporting::check_labels(sessions.value(), exporting::origin(db, options))) return *e;
  return Done{};
}

}  // namespace curvlab::harness::data
