// `curvlab export`: turns a session database into analysis formats (wide
// trial CSV, Psych-DS, BIDS motion). The formats live in curvlab_data.
#include "common.hpp"

#include "curvlab/harness/data/export.hpp"

#include <CLI/CLI.hpp>

#include <memory>

namespace curvlab::cli {
namespace {

struct ExportArgs {
  std::string db_path;
  std::string out_dir;
  std::string format = "all";
  std::int64_t session = 0;
  bool json = false;
};

void run_export(const ExportArgs& a, bool session_given) {
  if (a.out_dir.empty()) throw UsageError("--out must name a folder");
  auto db = data::Database::open(a.db_path, data::OpenMode::open_existing);
  if (!db) raise(db.error());
  data::ExportOptions options{a.out_dir, std::nullopt};
  if (session_given) options.session_id = a.session;
  Json doc;
  doc["db"] = a.db_path;
  doc["out"] = a.out_dir;
  Json files = Json::array();
  auto run = [&](const char* name, auto fn) {
    if (a.format != "all" && a.format != name) return;
    auto result = fn(db.value(), options);
    if (!result) raise(result.error());
    doc[std::string(name) + "_rows"] = result.value().rows;
    for (const auto& f : result.value().files) files.push_back(f);
  };
  run("csv", data::export_trials_csv);
  run("psychds", data::export_psychds);
  run("bids-motion", data::export_bids_motion);
  doc["files"] = files;
  if (!a.json) doc["files"] = std::to_string(files.size()) + " files";
  print_result(doc, a.json);
}

}  // namespace

void add_export_commands(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  auto* cmd = app.add_subcommand("export", "export session data: trial CSV, Psych-DS, BIDS motion");
  cmd->add_option("--db", args->db_path, "curvlab database file")->required();
  cmd->add_option("--out", args->out_dir, "output folder (created if missing)")->required();
  cmd->add_option("--format", args->format, "csv, psychds, bids-motion or all")
      ->check(CLI::IsMember({"csv", "psychds", "bids-motion", "all"}));
  auto* session = cmd->add_option("--session", args->session, "only this session id");
  cmd->add_flag("--json", args->json, "print the result as JSON");
  cmd->callback([args, session] { run_export(*args, session->count() > 0); });
}

}  // namespace curvlab::cli
