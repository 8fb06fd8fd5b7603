// `curvlab validate` and `curvlab design`: what an author runs while writing a
// protocol. Both only read the file; neither writes anything.
#include "common.hpp"
#include "station.hpp"

#include "curvlab/harness/runner/stimulus_checks.hpp"
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/settings_json.hpp"

#include <CLI/CLI.hpp>

#include <iostream>
#include <sstream>

namespace curvlab::harness::cli {
namespace {

namespace pr = curvlab::harness::protocol;

std::string duration_text(std::int64_t ms) {
  const std::int64_t s = (ms + 500) / 1000;
  return std::to_string(s / 60) + " min " + std::to_string(s % 60) + " s";
}

Json design_json(const pr::Protocol& p, const pr::Design& d, bool with_trials) {
  Json doc;
  doc["protocol"] = p.meta.name;
  doc["version"] = p.meta.version;
  doc["participant"] = d.participant;
  doc["protocol_seed"] = d.protocol_seed;
  doc["seed"] = d.seed;
  doc["block_order"] = std::string(pr::to_string(p.block_order));
  if (d.counterbalance_row) doc["counterbalance_row"] = *d.counterbalance_row + 1;
  Json blocks = Json::array();
  for (const auto& b : d.blocks) {
    Json jb;
    jb["name"] = b.name;
    jb["practice"] = b.practice;
    jb["trials"] = b.trial_count;
    blocks.push_back(jb);
  }
  doc["blocks"] = blocks;
  doc["total_trials"] = d.trials.size();
  doc["estimated_duration_s"] = static_cast<double>(d.estimated_duration_ms()) / 1000.0;
  if (!with_trials) return doc;
  Json trials = Json::array();
  for (const auto& t : d.trials) {
    Json jt;
    jt["index"] = t.index;
    jt["block"] = t.block;
    jt["trial_in_block"] = t.trial_in_block;
    jt["practice"] = t.practice;
    jt["repetition"] = t.repetition;
    Json lv = Json::object();
    for (const auto& [f, l] : t.levels) lv[f] = l;
    jt["levels"] = lv;
    jt["judgement"] = std::string(t.judgement->name());
    if (t.staircase) jt["staircase"] = t.staircase->index;
    if (t.adjustment_start) jt["adjustment_start"] = *t.adjustment_start;
    if (t.break_before) jt["break_before"] = true;
    jt["settings"] = pr::settings_json(t.settings, t.derived, pr::SettingsRecord::condition);
    trials.push_back(jt);
  }
  doc["trials"] = trials;
  return doc;
}

// One problem as `validate --json` lists it; line, column and field are
// null where the problem has none (a file that cannot be read).
Json diagnostic_json(const harness::Diagnostic& d) {
  Json j;
  j["file"] = d.file;
  j["line"] = d.pos.line > 0 ? Json(d.pos.line) : Json(nullptr);
  j["column"] = d.pos.line > 0 ? Json(d.pos.column) : Json(nullptr);
  j["field"] = d.field.empty() ? Json(nullptr) : Json(d.field);
  j["message"] = d.message;
  return j;
}

// A file that does not load, as one JSON document on stdout: every problem
// (exit 2, as without --json).
[[noreturn]] void reject_as_json(const std::string& file, const harness::Error& e) {
  Json doc;
  doc["ok"] = false;
  doc["file"] = file;
  Json list = Json::array();
  for (const auto& d : e.diagnostics) list.push_back(diagnostic_json(d));
  if (list.empty()) list.push_back(diagnostic_json({file, {}, "", e.message}));
  doc["diagnostics"] = list;
  // A file name need not be UTF-8; JSON must be.
  std::cout << doc.dump(2, ' ', false, Json::error_handler_t::replace) << '\n';
  throw UsageError(std::to_string(list.size()) + (list.size() == 1 ? " error" : " errors") + " in " + file);
}

// With --backend (and --responses): every answer must be one those devices
// can give, as run checks before a session starts.
void check_devices(const std::string& file, const pr::Protocol& p, const BackendArgs& devices, bool as_json) {
  if (devices.backend.empty()) return;
  if (devices.backend != "headless" && devices.backend != "desktop" && devices.backend != "xr")
    throw UsageError("--backend must be headless, desktop or xr, got '" + devices.backend + "'");
  const auto missing = unreachable_answer(with_protocol_responses(devices, p), p);
  if (!missing) return;
  if (as_json) reject_as_json(file, {harness::Error::Kind::bad_input, *missing, {{file, {}, "judgement", *missing}}});
  throw UsageError(*missing);
}

void run_validate(const std::string& file, bool as_json, const BackendArgs& devices) {
  if (as_json) {
    auto loaded = pr::load_protocol_file(file);
    if (!loaded) reject_as_json(file, loaded.error());
    check_devices(file, *loaded, devices, true);
    Json doc = design_json(*loaded, pr::expand_design(*loaded, 1), false);
    doc["ok"] = true;
    Json warnings = Json::array();
    for (const auto& w : harness::runner::protocol_warnings(*loaded))
      warnings.push_back({{"kind", harness::runner::to_string(w.kind)}, {"block", w.block}, {"condition", w.condition},
                          {"message", w.message}});
    doc["warnings"] = warnings;
    std::cout << doc.dump(2) << '\n';
    return;
  }
  const auto p = load_protocol_or_usage(file);
  check_devices(file, p, devices, false);
  const auto d = pr::expand_design(p, 1);
  std::cout << "OK " << file << ": " << p.meta.name << " " << p.meta.version << '\n';
  std::cout << "  seed " << p.seed << (p.seed_per_participant ? " (mixed with the participant number)" : "")
            << ", block order " << pr::to_string(p.block_order) << '\n';
  for (const auto& f : p.factors) {
    std::cout << "  factor " << f.name << (f.sets.empty() ? "" : " → " + f.sets) << ":";
    for (const auto& l : f.levels) std::cout << ' ' << l.label;
    std::cout << '\n';
  }
  for (const auto& b : d.blocks) {
    std::cout << "  block " << b.name << (b.practice ? " (practice)" : "") << ": " << b.trial_count
              << " trials";
    const auto& src = p.blocks.at(b.protocol_block);
    if (src.kind == "questionnaire") {
      std::cout << ", questionnaire " << src.instrument.name << " (" << src.instrument.items.size() << " items)\n";
      continue;
    }
    std::cout << ", " << src.judgement.type->name();
    if (src.judgement.type->stops_early()) std::cout << " (at most)";
    std::cout << '\n';
  }
  std::cout << "  total " << d.trials.size() << " trials, estimated duration "
            << duration_text(d.estimated_duration_ms())
            << " (timelines and breaks; instruction reading not included)\n";
  for (const auto& w : harness::runner::protocol_warnings(p)) std::cout << "warning: " << w.message << '\n';
}

void run_design(const std::string& file, std::uint64_t participant, bool as_json) {
  const auto p = load_protocol_or_usage(file);
  const auto d = pr::expand_design(p, static_cast<std::uint64_t>(participant));
  if (as_json) {
    std::cout << design_json(p, d, true).dump(2) << '\n';
    return;
  }
  std::cout << "# " << p.meta.name << " " << p.meta.version << ", participant " << participant
            << ", seed " << d.seed;
  if (d.counterbalance_row) std::cout << ", counterbalance row " << *d.counterbalance_row + 1;
  std::cout << "\n# index block trial practice judgement levels\n";
  for (const auto& t : d.trials) {
    std::cout << t.index << ' ' << t.block << ' ' << t.trial_in_block << ' ' << (t.practice ? "practice" : "-")
              << ' ' << t.judgement->name();
    for (const auto& [f, l] : t.levels) std::cout << ' ' << f << '=' << l;
    if (t.staircase) std::cout << " staircase=" << t.staircase->index;
    if (t.adjustment_start) std::cout << " start=" << *t.adjustment_start;
    if (t.break_before) std::cout << " [break before]";
    std::cout << '\n';
  }
}

}  // namespace

pr::Protocol load_protocol_or_usage(const std::string& path, std::string* text) {
  auto result = pr::load_protocol_file(path);
  if (result) {
    if (text) *text = result->text;
    return std::move(result).value();
  }
  for (const auto& d : result.error().diagnostics) std::cerr << pr::format_diagnostic(d) << '\n';
  const auto n = result.error().diagnostics.size();
  throw UsageError(std::to_string(n) + (n == 1 ? " error" : " errors") + " in " + path +
                   "; nothing was run or written");
}

void add_protocol_commands(CLI::App& app) {
  struct Args {
    std::string file;
    bool json = false;
    std::string participant;
    std::optional<std::uint64_t> participant_number;
    BackendArgs devices;  // validate --backend / --responses
  };
  auto args = std::make_shared<Args>();

  auto* validate = app.add_subcommand("validate", "check a protocol file; prints a summary or every error");
  validate->add_option("file", args->file, "protocol (TOML)")->required();
  validate->add_flag("--json", args->json, "print the summary as JSON");
  validate->add_option("--backend", args->devices.backend,
                       "also check that every answer can be given on this backend: headless, desktop or xr");
  validate->add_option("--responses", args->devices.responses,
                       "with --backend: HID devices that answer too, hid:MAPPING.toml (repeatable)");
  validate->callback([args] { run_validate(args->file, args->json, args->devices); });

  auto* design = app.add_subcommand("design", "print the expanded trial list for one participant");
  design->add_option("protocol", args->file, "protocol (TOML)")->required();
  design->add_option("--participant", args->participant,
                     "participant pseudonym or number, as run takes it (P07 and 7 give participant number 7)")
      ->required();
  design->add_option_function<std::uint64_t>("--participant-number",
                                             [args](std::uint64_t n) { args->participant_number = n; },
                                             "counterbalancing row and seed (default: the pseudonym's trailing "
                                             "number, else 1)");
  design->add_flag("--json", args->json, "print JSON (the list the runner stores)");
  design->callback([args] {
    run_design(args->file, participant_number(args->participant, args->participant_number), args->json);
  });
}

}  // namespace curvlab::harness::cli
