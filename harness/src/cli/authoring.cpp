// What an author runs before the first participant: `curvlab schema` (the
// protocol format as a JSON Schema, for editors and taplo), `curvlab new`
// (a protocol started from an example) and `curvlab preview` (a sheet of
// every condition's stimulus; runner/preview.hpp).
#include "common.hpp"

#include "curvlab/harness/runner/stimulus_checks.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/schema.hpp"
#include "curvlab/harness/runner/preview.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include "curvlab/harness/platform/files.hpp"
#include "curvlab/harness/platform/terminal.hpp"

namespace curvlab::harness::cli {
namespace {

namespace fs = std::filesystem;
namespace pr = curvlab::harness::protocol;

void run_schema(const std::string& out) {
  const std::string schema = pr::protocol_json_schema();
  if (out.empty()) {
    std::cout << schema;
    return;
  }
  std::ofstream f(out, std::ios::binary | std::ios::trunc);
  f << schema;
  f.close();
  if (!f) throw RuntimeFailure("cannot write " + out);
}

// ---- curvlab new ---------------------------------------------------------

bool is_protocol_name(const std::string& s) {
  if (s.empty() || s.size() > 64 || !(std::islower(static_cast<unsigned char>(s[0])) || s[0] == '_'))
    return false;
  return std::all_of(s.begin(), s.end(), [](char c) {
    return std::islower(static_cast<unsigned char>(c)) || std::isdigit(static_cast<unsigned char>(c)) ||
           c == '_' || c == '-';
  });
}

std::vector<std::string> example_names() {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(CURVLAB_PROTOCOLS_DIR, ec))
    if (e.path().extension() == ".toml") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

std::string toml_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

// Replaces `key = …` in [section] of the text, keeping the rest of the line's
// layout (indentation and a trailing comment); the copy keeps every comment
// of the example. Returns false when the key is not written in that section.
bool replace_value(std::string& text, const std::string& section, const std::string& key,
                   const std::string& value) {
  std::istringstream in(text);
  std::string line, out, current;
  bool done = false;
  while (std::getline(in, line)) {
    const auto first = line.find_first_not_of(" \t");
    const std::string body = first == std::string::npos ? "" : line.substr(first);
    if (!body.empty() && body[0] == '[') {
      const auto close = body.find(']');
      current = body.substr(body[1] == '[' ? 2 : 1, close == std::string::npos ? 0 : close - (body[1] == '[' ? 2 : 1));
    } else if (!done && current == section && body.rfind(key, 0) == 0) {
      const auto rest = body.substr(key.size());
      const auto eq = rest.find_first_not_of(" \t");
      if (eq != std::string::npos && rest[eq] == '=') {
        // A single-line value: keep a trailing comment after it.
        std::string comment;
        const auto hash = rest.rfind(" #");
        if (hash != std::string::npos && rest.find('"', hash) == std::string::npos) comment = rest.substr(hash);
        line = line.substr(0, first) + key + " = " + value + comment;
        done = true;
      }
    }
    out += line + '\n';
  }
  text = out;
  return done;
}

// The `#:schema` directive points at protocols/schema.json from wherever the
// new file lives.
void point_schema_directive(std::string& text, const fs::path& target_dir) {
  const fs::path schema = fs::path(CURVLAB_PROTOCOLS_DIR) / "schema.json";
  std::error_code ec;
  fs::path rel = fs::relative(schema, fs::absolute(target_dir), ec);
  std::string where = ec || rel.empty() ? schema.string() : rel.generic_string();
  if (where.find('/') == std::string::npos) where = "./" + where;
  const std::string directive = "#:schema " + where;
  if (text.rfind("#:schema", 0) == 0) {
    const auto eol = text.find('\n');
    text = directive + text.substr(eol == std::string::npos ? text.size() : eol);
  } else {
    text = directive + "\n" + text;
  }
}

struct NewArgs {
  std::string name, from = "demo", dir = "protocols";
  std::int64_t seed = -1;  // -1: a fresh random seed
  bool json = false;
};

void run_new(const NewArgs& a) {
  if (!is_protocol_name(a.name))
    throw UsageError("NAME: expected a lower-case identifier (a-z, 0-9, _ and -), found \"" + a.name + "\"");
  fs::path source = a.from;
  if (source.extension() != ".toml") {
    const auto names = example_names();
    if (std::find(names.begin(), names.end(), a.from) == names.end()) {
      std::string list;
      for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
      throw UsageError("--from: no example named \"" + a.from + "\"; expected one of: " + list +
                       " (or the path of a .toml file)");
    }
    source = fs::path(CURVLAB_PROTOCOLS_DIR) / (a.from + ".toml");
  }
  const fs::path target = fs::path(a.dir) / (a.name + ".toml");
  if (fs::exists(target))
    throw UsageError(target.string() + " already exists; curvlab new never overwrites a protocol "
                                       "(choose another NAME or remove the file)");
  // The example must itself be a protocol: the loader refuses a file over
  // its size limit (1 MiB) or one that does not load, as validate would.
  const auto example = pr::load_protocol_file(source.string());
  if (!example) {
    for (const auto& d : example.error().diagnostics) std::cerr << pr::format_diagnostic(d) << '\n';
    throw UsageError("--from " + source.string() + " is not a protocol that loads; nothing was written");
  }
  std::string text = example->text;
  std::uint64_t seed = static_cast<std::uint64_t>(a.seed);
  if (a.seed < 0) {
    std::random_device rd;
    seed = ((static_cast<std::uint64_t>(rd()) << 32) | rd()) >> 1;  // a TOML integer is signed
  }
  if (!replace_value(text, "protocol", "name", toml_string(a.name)) ||
      !replace_value(text, "protocol", "version", toml_string("0.1.0")) ||
      !replace_value(text, "randomization", "seed", std::to_string(seed)))
    throw UsageError(source.string() + ": expected name and version in [protocol] and seed in [randomization]");
  point_schema_directive(text, a.dir);
  // The copy must load exactly as the example did.
  const auto loaded = pr::load_protocol_text(text, target.string());
  if (!loaded) {
    for (const auto& d : loaded.error().diagnostics) std::cerr << pr::format_diagnostic(d) << '\n';
    throw UsageError("the copy of " + source.string() + " does not load; nothing was written");
  }
  std::error_code ec;
  fs::create_directories(a.dir, ec);
  if (ec) throw RuntimeFailure("cannot create " + a.dir + ": " + ec.message());
  // O_EXCL semantics: another process may have created the file meanwhile.
  std::FILE* f = platform::create_new_file(target.string());
  if (!f) throw UsageError(target.string() + " already exists or cannot be created; nothing was written");
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !ok) {
    fs::remove(target, ec);
    throw RuntimeFailure("cannot write " + target.string());
  }
  Json doc;
  doc["file"] = target.string();
  doc["from"] = source.string();
  doc["name"] = a.name;
  doc["version"] = "0.1.0";
  doc["seed"] = seed;
  if (a.json) {
    print_result(doc, true);
    return;
  }
  std::cout << "wrote " << target.string() << " (from " << source.string() << "; name \"" << a.name
            << "\", version 0.1.0, seed " << seed << ")\n"
            << "next: curvlab validate " << target.string() << ", then curvlab preview " << target.string()
            << " --out preview/" << a.name << '\n';
}

// ---- curvlab preview -------------------------------------------------------

struct PreviewArgs {
  std::string file, out, size;
  std::string participant = "1";
  std::optional<std::uint64_t> participant_number;
  bool software = false;
};

void run_preview(const PreviewArgs& a) {
  const std::uint64_t participant = participant_number(a.participant, a.participant_number);
  std::optional<std::pair<std::uint32_t, std::uint32_t>> size;
  if (!a.size.empty()) size = parse_size(a.size, "--size");
  std::string text;
  const auto p = load_protocol_or_usage(a.file, &text);
  harness::runner::PreviewRequest rq;
  rq.protocol_path = a.file;
  rq.protocol_text = text;
  rq.participant = participant;
  rq.out_dir = a.out;
  rq.size = size;
  rq.software = a.software;
  const bool tty = platform::stderr_is_terminal();
  rq.progress = [tty](std::size_t done, std::size_t total, const std::string& what) {
    constexpr int kWidth = 30;
    const int filled = total ? static_cast<int>(kWidth * done / total) : kWidth;
    std::cerr << (tty ? "\r" : "") << "rendering [" << std::string(static_cast<std::size_t>(filled), '#')
              << std::string(static_cast<std::size_t>(kWidth - filled), '.') << "] " << done << "/" << total
              << (what.empty() ? "" : "  " + what) << (tty ? "\033[K" : "\n") << std::flush;
    if (tty && done == total) std::cerr << '\n';
  };
  for (const auto& w : harness::runner::protocol_warnings(p)) std::cerr << "curvlab: warning: " << w.message << '\n';
  auto result = harness::runner::write_preview(p, rq);
  if (!result) raise(result.error());
  const auto& r = result.value();
  std::cout << "wrote " << r.index_html << ": " << r.conditions << " conditions, " << r.images
            << " images (" << r.device << ")\n";
}

}  // namespace

void add_authoring_commands(CLI::App& app) {
  auto schema_out = std::make_shared<std::string>();
  auto* schema = app.add_subcommand("schema", "print the protocol format as a JSON Schema (draft-07) for editors "
                                              "and taplo; protocols/schema.json holds the same text");
  schema->add_option("--out", *schema_out, "write it to FILE instead of standard output");
  schema->callback([schema_out] { run_schema(*schema_out); });

  auto na = std::make_shared<NewArgs>();
  auto* make = app.add_subcommand("new", "start a protocol: copies an example into protocols/NAME.toml with its "
                                         "name, version (0.1.0) and a fresh seed; never overwrites");
  make->add_option("name", na->name, "protocol name (a lower-case identifier; also the file name)")->required();
  make->add_option("--from", na->from, "example to copy (a name from protocols/, or a .toml path)")
      ->default_str("demo");
  make->add_option("--dir", na->dir, "folder the protocol is written to")->default_str("protocols");
  make->add_option("--seed", na->seed, "the seed to write, ≥ 0 (default: a fresh random one)")
      ->check(CLI::NonNegativeNumber);
  make->add_flag("--json", na->json, "print what was written as JSON");
  make->callback([na] { run_new(*na); });

  auto pa = std::make_shared<PreviewArgs>();
  auto* preview = app.add_subcommand("preview", "write DIR/index.html: every condition's onset stereo pair, "
                                                "predicted responses, block order, timeline and texts");
  preview->add_option("protocol", pa->file, "protocol (TOML)")->required();
  preview->add_option("--out", pa->out, "folder for index.html and its images (nothing is written elsewhere)")
      ->required();
  preview->add_option("--participant", pa->participant,
                      "participant pseudonym or number, as run takes it (P07 and 7 give participant number 7): "
                      "block order and seed")
      ->default_str("1");
  preview->add_option_function<std::uint64_t>("--participant-number",
                                              [pa](std::uint64_t n) { pa->participant_number = n; },
                                              "counterbalancing row and seed (default: the pseudonym's trailing "
                                              "number, else 1)");
  preview->add_option("--size", pa->size, "per-eye image size WxH (default: the protocol's resolution, at most "
                                          "480 px wide)");
  preview->add_flag("--software", pa->software, "render on lavapipe even with a GPU");
  preview->callback([pa] { run_preview(*pa); });
}

}  // namespace curvlab::harness::cli
