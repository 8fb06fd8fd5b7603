// `curvlab run | resume`: sessions of a protocol with a participant (or the
// simulated observer) and their continuation after a crash; `predict`
// (predict.cpp) and `replay` (replay.cpp) are registered after them.
#include "common.hpp"
#include "calibrate.hpp"
#include "lsl_args.hpp"
#include "shared_args.hpp"
#include "observer_args.hpp"
#include "station.hpp"

#include "curvlab/harness/data/database.hpp"
#include "curvlab/harness/data/export.hpp"
#include "curvlab/harness/data/writer_lock.hpp"
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/platform/signals.hpp"
#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/io/clock.hpp"
#include "curvlab/harness/operator/operator_window.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/runner/headless.hpp"
#include "curvlab/harness/runner/image_observer.hpp"
#include "curvlab/harness/runner/percept.hpp"
#include "curvlab/harness/runner/predict.hpp"
#include "curvlab/harness/runner/replay.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"
#include "curvlab/harness/runner/stimulus_checks.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/tracking/trajectory_csv.hpp"
#include "curvlab/harness/xr/backend.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <functional>
#include <set>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

namespace curvlab::harness::cli {
namespace {

namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;

// SIGINT (Ctrl-C), SIGTERM and SIGHUP (a closed terminal) end a session
// interrupted and flushed, with the resume command printed (station.hpp).
void watch_stop_signals(rn::RunOptions& o) { o.stop_signal = &catch_stop_signals(); }

void add_backend_options(CLI::App* cmd, BackendArgs& b) {
  cmd->add_option("--backend", b.backend, "headless (default), desktop or xr");
  cmd->add_option("--pace", b.pace, "headless: fast (simulated time, default) or realtime");
  cmd->add_option("--render", b.render,
                  "headless: draw all frames (default), only each stimulus onset, or none");
  cmd->add_option("--images", b.images, "save each trial's stimulus onset as PNGs in this folder");
  cmd->add_option("--trajectory", b.trajectory,
                  "headless: lab poses from a trajectory CSV (curvlab trajectory …), looped");
  cmd->add_option_function<std::string>("--msaa", [&b](const std::string& n) { b.msaa = n; },
                                        "samples per pixel: auto (4 on a GPU, 1 on a CPU device), 1, 2, 4 or 8 "
                                        "(default: the protocol's [viewing] msaa, itself auto by default)");
  cmd->add_flag("--software", b.software, "use a CPU Vulkan device (lavapipe) even with a GPU");
  cmd->add_option("--window-size", b.window_size, "desktop: per-eye size WxH (default 960x960)");
  cmd->add_option("--preview", b.preview, "desktop: side-by-side (default), left or right");
  cmd->add_option("--screenshot", b.screenshot, "desktop: save every stimulus onset and response window (and F12) here");
  cmd->add_option("--key-script", b.key_script,
                  "a file of scripted key presses (desktop; headless: they answer instead of the simulated observer)");
  cmd->add_option("--responses", b.responses,
                  "also answer from HID devices: hid:MAPPING.toml (repeatable; docs/devices.md)");
  cmd->add_option("--export", b.export_dir, "afterwards, export CSV, Psych-DS and BIDS motion here");
  cmd->add_flag("--quiet", b.quiet, "no progress bar");
  cmd->add_flag("--json", b.json, "print the summary as JSON");
  cmd->add_option("--progress", b.progress,
                  "bar (default: on a terminal's stderr; otherwise a line every --progress-interval-s) or json "
                  "(a line per trial on stdout)");
  cmd->add_option("--progress-interval-s", b.progress_interval_s,
                  "seconds between progress lines when stderr is not a terminal (default 10)");
  cmd->add_option("--operator-window", b.operator_window,
                  "the experimenter's window: auto (default: with --backend xr when a display exists), on or off");
  cmd->add_option("--operator-script", b.operator_script,
                  "operator actions from a file: SECONDS ACTION [TEXT] a line (docs/xr.md)");
  cmd->add_option("--operator-screenshot", b.operator_screenshot,
                  "save the operator window as PNG here at each action and at the end");
  cmd->add_option("--operator-eyes", b.operator_eyes, "the operator window shows both (default), left or right");
}

// Parsed before anything runs: a bad line stops the command (exit 2).
std::vector<rn::OperatorAction> read_operator_script(const BackendArgs& a) {
  if (a.operator_script.empty()) return {};
  auto script = rn::read_operator_script(a.operator_script);
  if (!script) raise(script.error());
  return std::move(script).value();
}

// The operator's console: the window (--operator-window), or the script
// alone, or none. Made after the display, so destroyed before it.
std::unique_ptr<rn::OperatorConsole> open_console(const BackendArgs& a, std::vector<rn::OperatorAction> script,
                                                  harness::io::Display& display, const std::string& db) {
  if (wants_operator_window(a)) {
    harness::operator_console::OperatorWindowOptions o;
    o.script = std::move(script);
    o.mirror = display.mirror();
    if (a.operator_eyes == "left") o.eyes = harness::operator_console::EyeView::left;
    else if (a.operator_eyes == "right") o.eyes = harness::operator_console::EyeView::right;
    o.screenshot_dir = a.operator_screenshot;
    o.db_dir = std::filesystem::path(db).parent_path().string();
    o.terminate_glfw = a.backend != "desktop";
    auto made = harness::operator_console::open_operator_window(std::move(o));
    if (!made) raise(made.error());
    return std::move(made).value();
  }
  if (!a.operator_screenshot.empty())
    throw UsageError("--operator-screenshot needs the operator window (--operator-window on, and a display)");
  if (script.empty()) return nullptr;
  return std::make_unique<rn::ScriptConsole>(std::move(script));
}

void check_operator_args(const BackendArgs& a) {
  if (a.progress != "bar" && a.progress != "json")
    throw UsageError("--progress must be bar or json, got '" + a.progress + "'");
  if (a.operator_eyes != "both" && a.operator_eyes != "left" && a.operator_eyes != "right")
    throw UsageError("--operator-eyes must be both, left or right, got '" + a.operator_eyes + "'");
  (void)wants_operator_window(a);
}


// What a key script must fit (desktop.hpp): each timed phase's shortest
// length over the blocks that show it (a play block's stimulus phase is the
// whole game; a questionnaire block shows only pages), and every key that
// answers. A phase no block shows lasts 0 ms.
desktop::KeyScriptLimits key_script_limits(const pr::Protocol& p) {
  desktop::KeyScriptLimits l;
  l.protocol = p.file;
  auto add_keys = [&l](const pr::Judgement& j) {
    for (const auto& option : j.options)
      for (const auto& key : option.keys) l.answer_keys.push_back(key);
  };
  std::optional<std::int64_t> fixation, stimulus, response, iti;
  auto shortest = [](std::optional<std::int64_t>& limit, std::int64_t ms) { limit = std::min(limit.value_or(ms), ms); };
  add_keys(p.judgement);
  for (const auto& b : p.blocks) {
    add_keys(b.judgement);
    if (b.kind == "play") shortest(stimulus, std::llround(b.play.duration_s * 1000.0));
    if (b.kind != "trials") continue;
    const auto t = p.block_settings(b).timeline;
    shortest(fixation, t.fixation_ms);
    shortest(stimulus, t.stimulus_ms);
    shortest(response, t.response_ms);
    shortest(iti, t.iti_ms);
  }
  if (p.blocks.empty()) {
    const auto t = p.session_settings().timeline;
    fixation = t.fixation_ms;
    stimulus = t.stimulus_ms;
    response = t.response_ms;
    iti = t.iti_ms;
  }
  l.fixation_ms = fixation.value_or(0);
  l.stimulus_ms = stimulus.value_or(0);
  l.response_ms = response.value_or(0);
  l.iti_ms = iti.value_or(0);
  return l;
}

// The samples per pixel: --msaa, else the protocol's [viewing] msaa. "auto"
// (nullopt) lets the display's renderer pick for its device; a count is
// clamped to the device, with a warning. The count drawn with is the
// display's (DisplayInfo::msaa), stored with the session.
Devices open_devices(const BackendArgs& a, const pr::Protocol& p, const geometry::PhysicalTableFit& table,
                     std::int64_t start_ns, const SharedArgs& shared) {
  StationNeeds n;
  n.stand_across = shared.role == "join";
  n.msaa = a.msaa ? parse_msaa(*a.msaa) : p.session_settings().viewing.msaa;
  n.refresh_hz = p.refresh_hz;
  n.width_px = static_cast<std::uint32_t>(p.resolution_width);
  n.height_px = static_cast<std::uint32_t>(p.resolution_height);
  n.table = table;
  n.start_ns = start_ns;
  n.key_script_limits = key_script_limits(p);
  return open_station(a, n);
}

rn::RunOptions drawing_options(const BackendArgs& a) {
  rn::RunOptions o;
  const auto drawing = rn::parse_frame_drawing(a.render);
  if (!drawing) throw UsageError("--render must be all, onset or none, got '" + a.render + "'");
  o.drawing = *drawing;
  o.images_dir = a.images;
  o.progress = !a.quiet && !a.json && a.progress == "bar";
  o.progress_json = a.progress == "json";
  if (!(a.progress_interval_s > 0.0 && a.progress_interval_s <= 86400.0))
    throw UsageError("--progress-interval-s must lie in (0, 86400] seconds");
  o.progress_every = std::chrono::milliseconds(std::llround(a.progress_interval_s * 1000.0));
  o.lossless_logging = a.backend == "headless" && a.pace == "fast";
  if (!a.images.empty()) {
    std::error_code ec;
    if (std::filesystem::exists(a.images, ec) && !std::filesystem::is_directory(a.images, ec))
      throw UsageError("--images " + a.images + ": is a file; expected a folder for the onset images (created when "
                       "missing)");
    std::filesystem::create_directories(a.images, ec);
    if (ec) throw RuntimeFailure("cannot create --images folder " + a.images + ": " + ec.message());
  }
  return o;
}

// The run options a session stores with its start (and each resume with
// itself), which `resume` takes as its defaults: how frames are drawn and
// paced, where onset images and exports go, who answers.
constexpr std::array<std::pair<const char*, std::string BackendArgs::*>, 4> kStoredRunOptions{{
    {"render", &BackendArgs::render},
    {"pace", &BackendArgs::pace},
    {"images", &BackendArgs::images},
    {"export", &BackendArgs::export_dir},
}};

std::string run_options_json(const BackendArgs& a, const std::string& observer) {
  Json j = Json::object();
  for (const auto& [name, field] : kStoredRunOptions) j[name] = a.*field;
  j["observer"] = observer;
  return j.dump();
}

// `resume`'s options: each stored run option the command line does not give.
// Returns the observer model the session ran with ("" when none recorded).
std::string apply_stored_run_options(BackendArgs& a, const std::string& stored_json,
                                     const std::function<bool(const std::string&)>& given) {
  const Json j = Json::parse(stored_json, nullptr, false);
  if (!j.is_object()) return {};
  for (const auto& [name, field] : kStoredRunOptions) {
    const std::string option = std::string("--") + name;
    if (const auto v = j.find(name); v != j.end() && v->is_string() && !given(option)) a.*field = v->get<std::string>();
  }
  const auto observer = j.find("observer");
  return observer != j.end() && observer->is_string() ? observer->get<std::string>() : std::string();
}

void export_all(const std::string& db_path, std::int64_t session_id, const std::string& dir, Json& doc) {
  auto db = data::Database::open(db_path, data::OpenMode::read_only);
  if (!db) raise(db.error());
  Json files = Json::array();
  for (const auto& format : data::export_formats()) {
    data::ExportOptions o;
    o.out_dir = (std::filesystem::path(dir) / format.run_folder).string();
    o.session_id = session_id;
    auto r = format.write(db.value(), o);
    if (!r) raise(r.error());
    for (const auto& f : r.value().files) files.push_back((std::filesystem::path(o.out_dir) / f).string());
  }
  doc["exports"] = files;
}

// The session's summary; `msaa` is the samples per pixel the display drew
// with (0: nothing drawn).
void report(const rn::RunResult& result, const BackendArgs& a, std::uint32_t msaa) {
  if (!result) raise(result.error());
  const auto& s = result.value();
  Json doc;
  doc["db"] = s.db_path;
  doc["session_id"] = s.session_id;
  doc["status"] = data::to_string(s.status);
  doc["trials_planned"] = s.trials_planned;
  doc["trials_completed"] = s.trials_completed;
  doc["trials_skipped"] = s.trials_skipped;
  doc["trials_aborted"] = s.trials_aborted;
  doc["trials_flagged"] = s.trials_flagged;
  doc["attempts_repeated"] = s.attempts_repeated;
  if (s.shots > 0) {
    doc["shots"] = s.shots;
    doc["balls_pocketed"] = s.balls_pocketed;
  }
  if (s.items_answered > 0) doc["items_answered"] = s.items_answered;
  if (!s.play.empty()) {
    Json play = Json::array();
    for (const auto& p : s.play)
      play.push_back(Json{{"block", p.block},
                          {"shots", p.shots},
                          {"pocketed", p.pocketed},
                          {"time_s", p.time_s},
                          {"walked_m", p.walked_m},
                          {"laps_physical", p.laps_physical},
                          {"laps_virtual", p.laps_virtual},
                          {"laps_ratio", p.laps_virtual != 0.0 ? p.laps_physical / p.laps_virtual : 0.0},
                          {"hand_error_m", p.hand_error_m}});
    doc["play"] = play;
  }
  doc["frames"] = s.frames;
  doc["msaa"] = msaa;
  doc["samples_dropped"] = s.samples_dropped;
  doc["session_s"] = s.session_s;
  doc["wall_s"] = s.wall_s;
  doc["frame_cpu_median_ms"] = s.frame_cpu_median_ms;
  doc["frame_cpu_p95_ms"] = s.frame_cpu_p95_ms;
  if (!a.images.empty()) {
    doc["images_dir"] = a.images;
    doc["images"] = s.images.size();
  }
  if (!a.export_dir.empty()) export_all(s.db_path, s.session_id, a.export_dir, doc);
  print_result(doc, a.json);
  if (s.status != data::SessionStatus::completed) {
    std::cerr << "session " << s.session_id << " stopped before the end; continue it with: curvlab resume --db "
              << s.db_path << " --session " << s.session_id << '\n';
    if (s.output_lost)
      throw RuntimeFailure("session interrupted: standard output was closed (the program reading --progress json "
                           "exited)");
    if (const int sig = stop_signal_received(); sig != 0)
      throw RuntimeFailure("session interrupted by signal " + std::to_string(sig) + " (" + platform::signal_name(sig) + ")",
                           128 + sig);
    throw RuntimeFailure("session interrupted");
  }
}

struct RunArgs {
  std::string protocol;
  std::string participant;
  std::optional<std::uint64_t> participant_number;
  std::string db;
  std::optional<double> ipd_m;
  std::string dominant_eye = "unknown";
  std::string calibration;
  bool new_session = false;
  std::string note;
  ObserverArgs observer;
  BackendArgs backend;
  LslArgs lsl;
  SharedArgs shared;
};

std::optional<geometry::PhysicalTableFit> read_calibration(const std::string& path) {
  if (path.empty()) return std::nullopt;
  std::ifstream in(path);
  if (!in) throw UsageError(path + ": cannot read the calibration file");
  std::stringstream text;
  text << in.rdbuf();
  auto fit = rn::parse_calibration_json(text.str(), path);
  if (!fit) throw UsageError(fit.error().message);
  return *fit;
}

// The protocol's [calibration] step runs before the session with a person
// at the devices (desktop, xr); a headless run's simulated participant has
// no hand to touch with, so it uses the nominal or --calibration table.
bool calibrates_at_start(const pr::Protocol& p, const BackendArgs& a) {
  return p.calibration.at_start && a.backend != "headless";
}

// The step's options: the table as known (--calibration, else nominal) and
// the protocol's tip offset and residual limit.
rn::CalibrationOptions calibration_options(const pr::Protocol& p, const geometry::PhysicalTableFit& known,
                                           const RunArgs& a, const rn::RunOptions& o) {
  rn::CalibrationOptions c;
  c.known = known;
  c.tip_offset_m = {p.calibration.tip_offset_m[0], p.calibration.tip_offset_m[1], p.calibration.tip_offset_m[2]};
  c.limits.max_residual_m = p.calibration.max_residual_mm / 1000.0;
  // The virtual table's edges equal the protocol's edge: the physical one
  // must measure the same.
  c.limits.known_edge_m = p.session_settings().table.edge_m;
  c.ipd_m = o.ipd_m.value_or(p.session_settings().viewing.ipd_m);
  c.width_px = static_cast<std::uint32_t>(p.resolution_width);
  c.height_px = static_cast<std::uint32_t>(p.resolution_height);
  c.screenshot_dir = a.backend.screenshot;
  c.stop_signal = o.stop_signal;
  return c;
}

void run_command(const RunArgs& a) {
  std::string text;
  const pr::Protocol p = load_protocol_or_usage(a.protocol, &text);
  rn::RunOptions o = drawing_options(a.backend);
  o.participant = a.participant;
  o.participant_number = participant_number(a.participant, a.participant_number);
  o.ipd_m = a.ipd_m;
  o.note = a.note;
  if (a.ipd_m && !(*a.ipd_m > 0.04 && *a.ipd_m < 0.09)) throw UsageError("--ipd-m must lie in (0.04, 0.09) m");
  if (a.dominant_eye == "left") o.dominant_eye = data::DominantEye::left;
  else if (a.dominant_eye == "right") o.dominant_eye = data::DominantEye::right;
  else if (a.dominant_eye != "unknown") throw UsageError("--dominant-eye must be left, right or unknown");
  o.calibration = read_calibration(a.calibration);
  if (a.backend.backend == "headless" && !a.backend.key_script.empty()) {
    // The script answers, in place of the simulated observer.
    if (a.observer.model != "human" && a.observer.model != "none")
      throw UsageError("--key-script answers in place of the simulated observer; drop --observer " + a.observer.model);
  } else if (a.backend.backend == "headless") {
    const std::uint64_t seed = pr::participant_seed(p.seed, o.participant_number, p.seed_per_participant);
    o.observer = observer_params(a.observer, pr::mix_seed(seed ^ 0x5eedULL));
    if (o.observer && o.observer->model == rn::ObserverModel::image)
      if (auto ok = rn::check_image_observer(p); !ok) throw UsageError(ok.error().message);
  }
  const std::string db = a.db.empty()
                             ? (std::filesystem::path("results") / (p.meta.name + ".sqlite")).string()
                             : a.db;
  check_db_argument(db);
  if (!a.new_session) check_participant_is_new(db, a.participant);
  const auto table = o.calibration.value_or(rn::nominal_calibration(p.session_settings()));
  check_operator_args(a.backend);
  auto script = read_operator_script(a.backend);
  const BackendArgs backend = with_protocol_responses(a.backend, p);
  check_answers_reachable(backend, p, o.observer.has_value());
  check_lsl_args(a.lsl, p, a.backend);
  check_shared_args(a.shared, p, a.backend);
  auto devices = open_devices(backend, p, table, 0, a.shared);
  auto streams = open_lsl(a.lsl, p, *devices.clock);
  o.streams = streams.get();
  watch_stop_signals(o);
  // The partner is found and compared before anything is written.
  auto shared = open_shared(a.shared, a.participant, p, text, *devices.clock, o.stop_signal);
  o.shared = shared.get();
  if (calibrates_at_start(p, a.backend)) o.calibration = calibrate_on(devices, calibration_options(p, table, a, o)).fit;
  if (const auto parent = std::filesystem::path(db).parent_path(); !parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
  }
  auto console = open_console(a.backend, std::move(script), *devices.station.display, db);
  o.console = console.get();
  o.run_options_json = run_options_json(a.backend, o.observer ? std::string(rn::to_string(o.observer->model)) : "none");
  for (const auto& w : rn::stimulus_warnings(p))
    if (w.kind == rn::StimulusWarningKind::model_range) o.warnings.push_back(w.message);
  auto result = rn::run_session(p, text, db, o, devices.station, *devices.clock);
  close_shared(shared.get(), result && result->status == data::SessionStatus::completed);
  console.reset();  // its last screenshot shows the session's end
  streams.reset();  // what its recorders still held is stored before the export
  report(result, a.backend, devices.station.display->info().msaa);
}

}  // namespace

void run_from_form(const FormRun& f) {
  RunArgs a;
  a.protocol = f.protocol;
  a.participant = f.participant;
  a.db = f.db;
  a.new_session = f.new_session;
  a.note = f.note;
  a.backend.backend = f.backend;
  a.backend.software = f.software;
  a.backend.window_size = f.window_size;
  run_command(a);
}

namespace {

struct ResumeArgs {
  std::string db;
  std::int64_t session = 0;
  ObserverArgs observer;
  bool observer_given = false;
  BackendArgs backend;
  LslArgs lsl;
  SharedArgs shared;
  std::set<std::string> given;  // the options on the command line ("--render")
};

void resume_command(ResumeArgs a) {
  check_db_argument(a.db);
  // Before a window or headset starts; resume_session holds the lock itself.
  if (const auto holder = data::WriterLock::session_writer(a.db, a.session))
    raise({harness::Error::Kind::in_use, data::session_in_use_message(a.db, a.session, *holder)});
  auto stored_v = rn::read_stored_session(a.db, a.session);
  if (!stored_v) raise(stored_v.error());
  const auto& stored = stored_v.value();
  // The session continues as it ran: its stored run options, unless the
  // command line gives others (which are then stored with the resume).
  std::string observer_model;
  if (stored.run_options_json)
    observer_model = apply_stored_run_options(a.backend, *stored.run_options_json,
                                              [&a](const std::string& name) { return a.given.contains(name); });
  auto loaded = pr::load_protocol_text(stored.protocol_text, stored.protocol_source);
  if (!loaded)
    throw RuntimeFailure("the stored protocol no longer loads: " +
                         pr::format_diagnostic(loaded.error().diagnostics.front()));
  rn::RunOptions o = drawing_options(a.backend);
  if (a.observer_given && a.backend.backend == "headless")
    o.observer = observer_params(a.observer, stored.observer ? stored.observer->seed : 1);
  const auto table = stored.calibration.value_or(rn::nominal_calibration(loaded->session_settings()));
  // A resumed session's clock continues after the last logged time.
  check_operator_args(a.backend);
  auto script = read_operator_script(a.backend);
  const BackendArgs backend = with_protocol_responses(a.backend, *loaded);
  check_answers_reachable(backend, *loaded, o.observer.has_value() || stored.observer.has_value());
  check_lsl_args(a.lsl, *loaded, a.backend);
  check_shared_args(a.shared, *loaded, a.backend);
  auto devices = open_devices(backend, *loaded, table, stored.last_t_ns + 1'000'000'000, a.shared);
  auto streams = open_lsl(a.lsl, *loaded, *devices.clock);
  o.streams = streams.get();
  auto console = open_console(a.backend, std::move(script), *devices.station.display, a.db);
  o.console = console.get();
  watch_stop_signals(o);
  if (o.observer) observer_model = rn::to_string(o.observer->model);
  else if (observer_model.empty()) observer_model = stored.observer ? rn::to_string(stored.observer->model) : "none";
  o.run_options_json = run_options_json(a.backend, observer_model);
  // A station that comes back rejoins its game (docs/shared_play.md, "Faults").
  auto shared = open_shared(a.shared, "", *loaded, stored.protocol_text, *devices.clock, o.stop_signal);
  o.shared = shared.get();
  auto result = rn::resume_session(a.db, a.session, stored, *loaded, o, devices.station, *devices.clock);
  close_shared(shared.get(), result && result->status == data::SessionStatus::completed);
  console.reset();
  streams.reset();
  report(result, a.backend, devices.station.display->info().msaa);
}

}  // namespace

void add_run_commands(CLI::App& app) {
  auto run = std::make_shared<RunArgs>();
  auto* r = app.add_subcommand("run", "run a session of a protocol (headless with the simulated observer by default)");
  r->add_option("protocol", run->protocol, "protocol file (TOML)")->required();
  r->add_option("--participant", run->participant, "participant pseudonym (no names)")->required();
  r->add_option_function<std::uint64_t>("--participant-number",
                                        [run](std::uint64_t n) { run->participant_number = n; },
                                        "counterbalancing row and seed (default: the pseudonym's trailing number, else 1)");
  r->add_option("--db", run->db, "SQLite file (default results/<protocol name>.sqlite)");
  r->add_option_function<double>("--ipd-m", [run](double v) { run->ipd_m = v; }, "participant's IPD in metres");
  r->add_option("--dominant-eye", run->dominant_eye, "left, right or unknown");
  r->add_flag("--new-session", run->new_session,
              "start another session of a pseudonym that already has one in --db (otherwise exit 2)");
  r->add_option("--note", run->note, "the experimenter's note, stored with the session's start (an operator_note event)");
  r->add_option("--calibration", run->calibration, "table calibration JSON (centre_x_m, centre_z_m, yaw_rad, edge_m, height_m)");
  add_observer_options(r, run->observer);
  add_backend_options(r, run->backend);
  add_lsl_options(r, run->lsl);
  add_shared_options(r, run->shared);
  r->callback([run] { run_command(*run); });

  auto res = std::make_shared<ResumeArgs>();
  auto* rs = app.add_subcommand("resume", "continue an interrupted session from its first incomplete trial");
  rs->add_option("--db", res->db, "SQLite file")->required();
  rs->add_option("--session", res->session, "session id")->required();
  add_observer_options(rs, res->observer);
  add_backend_options(rs, res->backend);
  add_lsl_options(rs, res->lsl);
  add_shared_options(rs, res->shared);
  rs->callback([res, rs] {
    res->observer_given = false;
    res->given.clear();
    for (const CLI::Option* opt : rs->get_options()) {
      if (opt->count() > 0) res->given.insert(opt->get_name());
      if (opt->get_name().starts_with("--observer") && opt->count() > 0) res->observer_given = true;
    }
    resume_command(*res);
  });

  add_predict_command(app);
  add_replay_command(app);
}

}  // namespace curvlab::harness::cli
