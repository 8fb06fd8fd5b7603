// `curvlab merge`: pools the files of a study's machines into one study
// database (curvlab_data's merge_databases) and prints what each input
// added. Conflicts leave the output unchanged and exit with code 2.
#include "common.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/merge.hpp"
#include "curvlab/harness/data/writer_lock.hpp"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

namespace curvlab::harness::cli {

std::vector<std::string> expand_database_args(const std::vector<std::string>& args, const std::string& exclude) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  std::error_code ec;
  for (const std::string& arg : args) {
    if (!fs::is_directory(arg, ec)) {
      files.push_back(arg);
      continue;
    }
    auto found = data::database_files_in(arg);
    if (!found) raise(found.error());
    for (const std::string& f : found.value())
      if (exclude.empty() || !fs::exists(exclude, ec) || !fs::equivalent(f, exclude, ec)) files.push_back(f);
  }
  return files;
}

namespace {

struct MergeArgs {
  std::string out;
  std::vector<std::string> inputs;
  bool allow_protocol_versions = false;
  bool json = false;
};

Json report_json(const data::MergeInputReport& r) {
  return {{"input", r.path},
          {"sessions_added", r.sessions_added},
          {"sessions_skipped", r.sessions_skipped},
          {"sessions_conflicting", r.sessions_conflicting},
          {"sessions_renumbered", r.sessions_renumbered},
          {"trials", r.trials},
          {"samples", r.samples},
          {"frames", r.frames}};
}

data::MergeInputReport totals(const std::vector<data::MergeInputReport>& inputs) {
  data::MergeInputReport t{"total"};
  for (const auto& r : inputs) {
    t.sessions_added += r.sessions_added;
    t.sessions_skipped += r.sessions_skipped;
    t.sessions_conflicting += r.sessions_conflicting;
    t.sessions_renumbered += r.sessions_renumbered;
    t.trials += r.trials;
    t.samples += r.samples;
    t.frames += r.frames;
  }
  return t;
}

void print_table(const data::MergeReport& report, const std::string& out) {
  std::size_t width = 5;
  for (const auto& r : report.inputs) width = std::max(width, r.path.size());
  const auto w = static_cast<int>(width);
  std::cout << std::left << std::setw(w) << "input" << std::right << std::setw(7) << "added" << std::setw(9)
            << "skipped" << std::setw(13) << "conflicting" << std::setw(12) << "renumbered" << std::setw(9)
            << "trials" << std::setw(10) << "samples" << std::setw(9) << "frames" << '\n';
  auto row = [&](const data::MergeInputReport& r) {
    std::cout << std::left << std::setw(w) << r.path << std::right << std::setw(7) << r.sessions_added
              << std::setw(9) << r.sessions_skipped << std::setw(13) << r.sessions_conflicting << std::setw(12)
              << r.sessions_renumbered << std::setw(9) << r.trials << std::setw(10) << r.samples << std::setw(9)
              << r.frames << '\n';
  };
  for (const auto& r : report.inputs) row(r);
  row(totals(report.inputs));
  std::cout << "output: " << out << (report.output_changed ? " (written)" : " (unchanged)") << '\n';
}

void run_merge(const MergeArgs& a) {
  data::MergeOptions opts{a.out, expand_database_args(a.inputs, a.out), a.allow_protocol_versions};
  auto report = data::merge_databases(opts);
  if (!report) raise(report.error());
  const auto& r = report.value();
  if (a.json) {
    Json doc{{"out", a.out}, {"output_changed", r.output_changed}};
    doc["inputs"] = Json::array();
    for (const auto& in : r.inputs) doc["inputs"].push_back(report_json(in));
    doc["total"] = report_json(totals(r.inputs));
    doc["conflicts"] = Json::array();
    for (const auto& c : r.conflicts) doc["conflicts"].push_back({{"session_uuid", c.session_uuid}, {"detail", c.detail}});
    std::cout << doc.dump(2) << '\n';
  } else {
    print_table(r, a.out);
  }
  if (r.conflicts.empty()) return;
  std::string message = "refused: " + std::to_string(r.conflicts.size()) +
                        " session(s) appear twice with different content; " + a.out + " was left unchanged";
  for (const auto& c : r.conflicts) message += "\n  session " + c.session_uuid + ": " + c.detail;
  throw UsageError(message);
}

// Migrates a file to the current schema in place: the one command that
// changes an older file (export, replay and merge read it unchanged).
void run_upgrade(const std::string& path, bool json) {
  check_db_argument(path);
  auto lock = data::WriterLock::for_replacing(path);
  if (!lock) raise(lock.error());
  const auto before = [&] {
    auto db = data::Database::open(path, data::OpenMode::read_only);
    if (!db) raise(db.error());
    return data::stored_schema_version(path);
  }();
  auto db = data::Database::open(path, data::OpenMode::open_existing);
  if (!db) raise(db.error());
  Json doc{{"db", path}, {"schema_version_before", before}, {"schema_version", db.value().schema_version()}};
  print_result(doc, json);
}

}  // namespace

void add_merge_commands(CLI::App& app) {
  auto* up = app.add_subcommand("upgrade", "migrate an older data file to the current schema in place");
  auto up_db = std::make_shared<std::string>();
  auto up_json = std::make_shared<bool>(false);
  up->add_option("--db", *up_db, "curvlab database file")->required();
  up->add_flag("--json", *up_json, "print the result as JSON");
  up->callback([up_db, up_json] { run_upgrade(*up_db, *up_json); });

  auto args = std::make_shared<MergeArgs>();
  auto* cmd = app.add_subcommand("merge", "pool session databases from several machines into one study database");
  cmd->add_option("--out", args->out, "study database (created when missing, else added to)")->required();
  cmd->add_option("inputs", args->inputs, "curvlab database files, or folders of *.sqlite files")->required();
  cmd->add_flag("--allow-protocol-versions", args->allow_protocol_versions,
                "pool sessions that ran different texts of one protocol name");
  cmd->add_flag("--json", args->json, "print the summary as JSON");
  cmd->callback([args] { run_merge(*args); });
}

}  // namespace curvlab::harness::cli
