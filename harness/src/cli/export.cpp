// `curvlab export`: turns session databases into analysis formats (wide
// trial CSV, Psych-DS, BIDS motion). The formats live in curvlab_data.
// Several files (or folders of them) are pooled first into a temporary study
// database exactly as `curvlab merge` would pool them, so exporting the
// separate files and exporting their merged file give the same rows.
#include "common.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/export.hpp"
#include "curvlab/harness/data/merge.hpp"
#include "curvlab/harness/data/staging.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <memory>
#include "curvlab/harness/platform/process.hpp"

namespace curvlab::harness::cli {
namespace {

namespace fs = std::filesystem;

struct ExportArgs {
  std::vector<std::string> db_paths;
  std::string out_dir;
  std::string format = "all";
  std::int64_t session = 0;
  bool json = false;
};

// The pooled copy of several inputs; removed when the export is done.
class PooledInputs {
 public:
  explicit PooledInputs(const std::vector<std::string>& inputs)
      : path_((fs::temp_directory_path() / ("curvlab-export-" + std::to_string(platform::process_id()) + ".sqlite")).string()) {
    // An export killed while pooling leaves its copy behind.
    data::remove_stale_staging(fs::temp_directory_path().string(), "curvlab-export-", data::StagingKind::database);
    data::remove_database_files(path_);
    auto merged = data::merge_databases({path_, inputs, true});
    if (!merged) raise(merged.error());
    if (merged.value().conflicts.empty()) return;
    const auto& c = merged.value().conflicts.front();
    throw UsageError("the inputs disagree about session " + c.session_uuid + ": " + c.detail +
                     " (curvlab merge lists every conflict)");
  }
  ~PooledInputs() { data::remove_database_files(path_); }
  PooledInputs(const PooledInputs&) = delete;
  PooledInputs& operator=(const PooledInputs&) = delete;
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

std::string joined(const std::vector<std::string>& paths) {
  std::string out;
  for (const auto& p : paths) out += (out.empty() ? "" : ", ") + p;
  return out;
}

void write_exports(data::Database& db, const ExportArgs& a, const data::ExportOptions& options, Json& doc) {
  std::vector<const data::ExportFormat*> chosen;
  for (const auto& format : data::export_formats())
    if (a.format == "all" || a.format == format.name) chosen.push_back(&format);
  // Labels that would collide refuse the export before any format is written.
  if (std::any_of(chosen.begin(), chosen.end(), [](const auto* f) { return f->files_named_after_labels; }))
    if (auto ok = data::check_export_labels(db, options); !ok) raise(ok.error());
  Json files = Json::array();
  for (const auto* format : chosen) {
    auto result = format->write(db, options);
    if (!result) raise(result.error());
    doc[std::string(format->name) + "_rows"] = result.value().rows;
    for (const auto& f : result.value().files) files.push_back(f);
  }
  doc["files"] = files;
  if (!a.json) doc["files"] = std::to_string(files.size()) + " files";
}

void run_export(const ExportArgs& a, bool session_given) {
  if (a.out_dir.empty()) throw UsageError("--out must name a folder");
  const bool single = a.db_paths.size() == 1 && !fs::is_directory(a.db_paths.front());
  const auto inputs = single ? a.db_paths : expand_database_args(a.db_paths, "");
  if (!single && session_given)
    throw UsageError("--session selects a session of one file; with several files export them all, or "
                     "export one file");
  std::unique_ptr<PooledInputs> pooled;
  if (!single) pooled = std::make_unique<PooledInputs>(inputs);
  auto db = data::Database::open(single ? inputs.front() : pooled->path(), data::OpenMode::read_only);
  if (!db) raise(db.error());
  // The description names the files, not their folders (docs/data.md, "Privacy").
  std::vector<std::string> names;
  for (const auto& input : inputs) names.push_back(fs::path(input).filename().string());
  data::ExportOptions options{a.out_dir, std::nullopt, single ? "" : joined(names)};
  if (session_given) options.session_id = a.session;
  Json doc;
  doc["db"] = single ? inputs.front() : joined(inputs);
  doc["out"] = a.out_dir;
  write_exports(db.value(), a, options, doc);
  print_result(doc, a.json);
}

}  // namespace

void add_export_commands(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  auto* cmd = app.add_subcommand("export", "export session data: trial CSV, Psych-DS, BIDS motion");
  cmd->add_option("--db", args->db_paths,
                  "curvlab database file; several files or folders of *.sqlite files are pooled as by merge")
      ->required();
  cmd->add_option("--out", args->out_dir, "output folder (created if missing)")->required();
  std::vector<std::string> names;
  for (const auto& format : data::export_formats()) names.emplace_back(format.name);
  std::string help;
  for (const auto& n : names) help += (help.empty() ? "" : ", ") + n;
  names.emplace_back("all");
  cmd->add_option("--format", args->format, help + " or all")->check(CLI::IsMember(names));
  auto* session = cmd->add_option("--session", args->session, "only this session id (one file only)");
  cmd->add_flag("--json", args->json, "print the result as JSON");
  cmd->callback([args, session] { run_export(*args, session->count() > 0); });
}

}  // namespace curvlab::harness::cli
