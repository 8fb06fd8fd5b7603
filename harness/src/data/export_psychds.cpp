// Psych-DS: dataset_description.json (schema.org Dataset, JSON-LD) with a
// PropertyValue in variableMeasured for every column, and one CSV per
// session in data/, named by keyword-value pairs ending in _data.csv.
#include "export_common.hpp"

#include "curvlab/harness/version.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace curvlab::harness::data {

using namespace exporting;

namespace {

// A table beside the trials, written per session as a file whose name adds
// the task keyword: play blocks' shots (task-play), questionnaire answers
// (task-questionnaire) and scores (task-questionnairescores).
struct TaskTable {
  std::string task;
  const TrialTable* table = nullptr;
};

// The dataset in `root` (the psychds folder); `source` names the data's
// origin in the description.
Expected<ExportSummary> write_dataset(const std::string& root, const std::vector<SessionInfo>& sessions,
                                      const TrialTable& table, const std::vector<TaskTable>& tasks,
                                      const std::string& source) {
  if (auto e = make_dir(root + "/data")) return *e;
  ExportSummary summary;
  for (const SessionInfo& s : sessions) {
    const std::string name = "data/study-" + alnum_label(s.protocol_name) + "_subject-" +
                             alnum_label(s.pseudonym) + "_session-" +
                             std::to_string(s.session_number) + "_data.csv";
    const CsvText csv = render_csv(table, s.session_id);
    if (auto e = write_text(root + "/" + name, csv.text)) return *e;
    summary.files.push_back("psychds/" + name);
    summary.rows += csv.rows;
    // The session's rows of each task table, where it has any (same
    // keywords, the task added).
    for (const TaskTable& task : tasks) {
      const CsvText task_csv = render_csv(*task.table, s.session_id);
      if (task_csv.rows == 0) continue;
      const std::string task_name = "data/study-" + alnum_label(s.protocol_name) + "_subject-" +
                                    alnum_label(s.pseudonym) + "_session-" + std::to_string(s.session_number) +
                                    "_task-" + task.task + "_data.csv";
      if (auto e = write_text(root + "/" + task_name, task_csv.text)) return *e;
      summary.files.push_back("psychds/" + task_name);
    }
  }

  nlohmann::ordered_json doc;
  doc["@context"] = "https://schema.org/";
  doc["@type"] = "Dataset";
  doc["name"] = "curvlab trial data";
  doc["description"] =
      "One row per trial of perception experiments in curved spaces (S3, E3, H3), exported by "
      "curvlab " + std::string(software_version()) + " from " + source + ". Missing values are NA.";
  doc["keywords"] = nlohmann::ordered_json::array({"perception", "virtual reality", "curved space"});
  doc["dateCreated"] = sessions.empty() ? "" : sessions.front().started_utc;
  auto& vars = doc["variableMeasured"] = nlohmann::ordered_json::array();
  std::vector<Column> described = table.columns;
  for (const TaskTable& task : tasks) {
    if (task.table->rows.empty()) continue;
    for (const Column& c : task.table->columns) {
      bool known = false;
      for (const Column& d : described) known = known || d.name == c.name;
      if (!known) described.push_back(c);
    }
  }
  for (const Column& c : described) {
    nlohmann::ordered_json v;
    v["@type"] = "PropertyValue";
    v["name"] = c.name;
    v["description"] = c.description;
    if (!c.unit.empty()) v["unitText"] = c.unit;
    vars.push_back(std::move(v));
  }
  if (auto e = write_text(root + "/dataset_description.json", doc.dump(2) + "\n")) return *e;
  summary.files.insert(summary.files.begin(), "psychds/dataset_description.json");
  return summary;
}

}  // namespace

Expected<ExportSummary> export_psychds(Database& db, const ExportOptions& options) {
  auto sessions = load_sessions(db, options);
  if (!sessions) return sessions.error();
  if (auto e = check_labels(sessions.value(), origin(db, options))) return *e;
  auto table = load_trial_table(db, options);
  if (!table) return table.error();
  auto shots = load_shot_table(db, options);
  if (!shots) return shots.error();
  auto answers = load_questionnaire_table(db, options);
  if (!answers) return answers.error();
  auto scores = load_questionnaire_score_table(db, options);
  if (!scores) return scores.error();
  const std::vector<TaskTable> tasks{
      {"play", &shots.value()}, {"questionnaire", &answers.value()}, {"questionnairescores", &scores.value()}};
  const std::string source =
      options.source.empty() ? std::filesystem::path(db.path()).filename().string() : options.source;
  return write_staged(options.out_dir, "psychds", true, [&](const std::string& root) {
    return write_dataset(root, sessions.value(), table.value(), tasks, source);
  });
}

}  // namespace curvlab::harness::data
