// curvlab start: the session start form in the desktop window, then the
// session it describes, run as `curvlab run` runs it.
#include "common.hpp"

#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/desktop/start_form.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/protocol/diagnostic.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <memory>

namespace curvlab::harness::cli {
namespace {

struct StartArgs {
  std::string db = "results/sessions.sqlite";
  std::string protocols = "protocols";
  std::string window_size = "960x960";
  bool software = false;
};

// The protocol files of a folder, sorted by name.
std::vector<std::string> protocol_files(const std::string& folder) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(folder, ec))
    if (entry.is_regular_file() && entry.path().extension() == ".toml") out.push_back(entry.path().string());
  if (ec) throw UsageError("--protocols " + folder + ": cannot read the folder (" + ec.message() + ")");
  std::sort(out.begin(), out.end());
  if (out.empty()) throw UsageError("--protocols " + folder + ": no protocol files (*.toml) in the folder");
  return out;
}

void start_command(const StartArgs& a) {
  check_db_argument(a.db);
  desktop::StartFormSetup setup;
  setup.db = a.db;
  setup.protocols = protocol_files(a.protocols);
  std::vector<std::string> pseudonyms;
  for (const auto& [pseudonym, sessions] : participants_in(a.db)) {
    setup.known.push_back({pseudonym, sessions});
    pseudonyms.push_back(pseudonym);
  }
  setup.similar_known = [pseudonyms](const std::string& p) {
    const std::string near = protocol::closest_match(p, pseudonyms);
    if (near.empty() || protocol::edit_distance(near, p) > 1) return std::string();
    // The next number of a series (P02 after P01) is not a typing slip.
    auto stem = [](const std::string& s) { return s.substr(0, s.find_last_not_of("0123456789") + 1); };
    const bool numbered = stem(p).size() < p.size() && stem(near).size() < near.size();
    return numbered && stem(p) == stem(near) ? std::string() : near;
  };
  desktop::StartForm form(std::move(setup));
  std::optional<desktop::StartChoices> chosen;
  {
    io::SteadyClock clock;
    desktop::DesktopOptions o;
    std::tie(o.eye_width_px, o.eye_height_px) = parse_size(a.window_size, "--window-size");
    o.preview = desktop::DesktopPreview::left;
    o.software = a.software;
    o.clock = &clock;
    auto window = desktop::make_desktop_backend(o);
    if (!window) raise(window.error());
    chosen = desktop::run_start_form(*window.value(), form, CURVLAB_DEFAULT_FONT);
  }  // the form's window closes before the session opens its own
  if (!chosen) {
    std::cout << "start form closed: no session started\n";
    return;
  }
  std::cout << "starting: curvlab run " << shell_word(chosen->protocol) << " --participant "
            << shell_word(chosen->participant) << " --db " << shell_word(a.db) << " --backend " << chosen->backend
            << (chosen->new_session ? " --new-session" : "")
            << (chosen->note.empty() ? "" : " --note " + shell_word(chosen->note)) << '\n';
  run_from_form({chosen->protocol, chosen->participant, a.db, chosen->backend, chosen->note, a.window_size,
                 chosen->new_session, a.software});
}

}  // namespace

void add_start_command(CLI::App& app) {
  auto args = std::make_shared<StartArgs>();
  auto* s = app.add_subcommand("start", "the session start form in a window (pseudonym, protocol, backend, note), "
                                        "then the session, as run would start it");
  s->add_option("--db", args->db, "SQLite file the sessions go to (default results/sessions.sqlite)");
  s->add_option("--protocols", args->protocols, "folder of protocol files to choose from (default protocols)");
  s->add_option("--window-size", args->window_size, "the window's size WxH per eye (default 960x960)");
  s->add_flag("--software", args->software, "use a CPU Vulkan device (lavapipe) even with a GPU");
  s->callback([args] { start_command(*args); });
}

}  // namespace curvlab::harness::cli
