// The only code that knows the protocol file is TOML. It walks the document
// once, reporting every problem with its position, then checks the design as
// a whole (every factor-level combination of every block), so an author sees
// all errors in one pass.
#include "curvlab/harness/protocol/loader.hpp"

#include "loader_impl.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace curvlab::harness::protocol {
namespace {

namespace tr = toml_reader;
using tr::type_name;

constexpr std::size_t kMaxFileBytes = 1u << 20;

// Every problem of a file as one failure; the message names the first, for
// a caller that shows only the message.
Error load_failure(Error::Kind kind, std::vector<Diagnostic> diagnostics) {
  std::string message = format_diagnostic(diagnostics.front());
  if (diagnostics.size() > 1) message += " (and " + std::to_string(diagnostics.size() - 1) + " more)";
  return {kind, std::move(message), std::move(diagnostics)};
}

}  // namespace

Result<Protocol> Loader::run(std::string_view text) {
  auto parsed = tr::parse(text, file());
  if (const auto* problem = std::get_if<tr::SyntaxProblem>(&parsed)) {
    error(to_source_pos(problem->pos), "syntax", problem->message);
    return load_failure(Error::Kind::bad_input, take_diagnostics());
  }
  const toml::table& root = std::get<toml::table>(parsed);
  Protocol p;
  p.file = file();
  p.text = std::string(text);
  read_root(root, p);
  if (!failed()) check_design(p, root);
  if (auto diagnostics = take_diagnostics(); !diagnostics.empty())
    return load_failure(Error::Kind::bad_input, std::move(diagnostics));
  return p;
}

void Loader::read_settings(const toml::table& t, const std::string& prefix, std::vector<SettingOverride>& out) {
  for (const char* section : {"space", "tracking", "viewing", "timeline", "stimulus", "table"}) {
    const std::string sp = join(prefix, section);
    const toml::table* st = sub_table(t, section, prefix);
    if (!st) continue;
    check_keys(*st, sp, setting_keys(section));
    if (st->contains("preset") && (st->contains("projection") || st->contains("eyes")))
      error(pos_of(*st->get("preset")), sp + ".preset",
            "a preset sets projection and eyes; give either the preset or projection/eyes");
    for (auto&& [k, v] : *st) {
      const std::string path = std::string(section) + "." + std::string(k.str());
      const SettingInfo* info = find_setting(path);
      if (!info) continue;  // reported by check_keys
      const auto value = to_value(v);
      if (!value) {
        error(pos_of(v), join(prefix, path), with_found("expected a value, found " + type_name(v), v));
        continue;
      }
      if (const auto checked = check_setting(*info, *value); !checked) {
        error(pos_of(v), join(prefix, path), with_found(checked.error().message, v));
        continue;
      }
      out.push_back({path, *value, pos_of(v)});
    }
  }
}

void Loader::read_root(const toml::table& root, Protocol& p) {
  check_keys(root, "", {"protocol", "space", "tracking", "viewing", "timeline", "stimulus",
                        "table", "backend", "calibration", "responses", "randomization", "counterbalance", "session",
                        "factors", "judgement", "instructions", "blocks", "lsl", "instruments"});
  read_metadata(root, p);
  read_settings(root, "", p.session_overrides);
  read_backend(root, p);
  read_calibration(root, p);
  if (const toml::table* r = sub_table(root, "responses", "")) {
    check_keys(*r, "responses", {"hid"});
    p.hid_mappings = get_string_array(*r, "hid", "responses");
  }
  if (const toml::table* l = sub_table(root, "lsl", "")) {
    check_keys(*l, "lsl", {"outlets"});
    p.lsl_outlets = get_bool(*l, "outlets", "lsl").value_or(false);
  }
  read_randomization(root, p);
  read_factors(root, p);
  // A top-level [judgement] is required unless every block has its own
  // (checked in read_blocks, where that is known).
  has_root_judgement_ = root.contains("judgement");
  if (const toml::table* j = sub_table(root, "judgement", "")) p.judgement = read_judgement(*j, "judgement", p);
  // A session value for a setting a factor varies would never be used.
  for (const auto& o : p.session_overrides)
    for (const auto& f : p.factors)
      if (f.sets == o.path)
        error(o.pos, o.path, "factor \"" + f.name + "\" varies " + f.sets +
                                 ", so this value would never be used; remove it");
  if (const toml::table* ins = sub_table(root, "instructions", "")) {
    check_keys(*ins, "instructions", {"start", "end"});
    p.instructions_start = get_string_array(*ins, "start", "instructions");
    p.instructions_end = get_string_array(*ins, "end", "instructions");
  }
  read_instruments(root, p);
  read_blocks(root, p);
  read_counterbalance(root, p);
}

void Loader::read_metadata(const toml::table& root, Protocol& p) {
  const toml::table* m = sub_table(root, "protocol", "");
  if (!m) {
    if (!root.contains("protocol"))
      error({1, 1}, "protocol", "missing required table [protocol] with name and version");
    return;
  }
  check_keys(*m, "protocol", {"name", "version", "description"});
  p.meta.name = get_string(*m, "name", "protocol", true).value_or("");
  p.meta.version = get_string(*m, "version", "protocol", true).value_or("");
  p.meta.description = get_string(*m, "description", "protocol", false).value_or("");
  if (m->contains("name") && m->get("name")->is_string() && p.meta.name.empty())
    error(pos_of(*m->get("name")), "protocol.name", "expected a non-empty name");
}

void Loader::read_backend(const toml::table& root, Protocol& p) {
  const toml::table* b = sub_table(root, "backend", "");
  if (!b) return;
  check_keys(*b, "backend", {"preferred", "refresh_hz", "resolution"});
  p.backend_preferred = get_enum(*b, "preferred", "backend", {"headless", "desktop", "xr"}).value_or("headless");
  p.refresh_hz = static_cast<int>(get_int(*b, "refresh_hz", "backend", 30, 240, false).value_or(90));
  if (const toml::node* r = b->get("resolution")) {
    const auto* arr = r->as_array();
    const toml::value<std::int64_t>* wn = arr && arr->size() == 2 ? (*arr)[0].as_integer() : nullptr;
    const toml::value<std::int64_t>* hn = arr && arr->size() == 2 ? (*arr)[1].as_integer() : nullptr;
    if (!wn || !hn) {
      error(pos_of(*r), "backend.resolution", "expected [width, height] in pixels, two integers");
    } else {
      const auto w = wn->get(), h = hn->get();
      if (w < 16 || w > 8192 || h < 16 || h > 8192)
        error(pos_of(*r), "backend.resolution",
              "expected each size in [16, 8192] pixels, got [" + std::to_string(w) + ", " + std::to_string(h) +
                  "]");
      else {
        p.resolution_width = static_cast<int>(w);
        p.resolution_height = static_cast<int>(h);
      }
    }
  }
}

void Loader::read_calibration(const toml::table& root, Protocol& p) {
  const toml::table* c = sub_table(root, "calibration", "");
  if (!c) return;
  check_keys(*c, "calibration", {"at_start", "tip_offset_m", "max_residual_mm"});
  p.calibration.at_start = get_bool(*c, "at_start", "calibration").value_or(false);
  if (const toml::node* t = c->get("tip_offset_m")) {
    const auto* arr = t->as_array();
    bool ok = arr != nullptr && arr->size() == 3;
    for (std::size_t i = 0; ok && i < 3; ++i) {
      const auto v = node_number((*arr)[i]);
      ok = v && std::abs(*v) <= 0.5;
      if (ok) p.calibration.tip_offset_m[i] = *v;
    }
    if (!ok)
      error(pos_of(*t), "calibration.tip_offset_m",
            with_found("expected [x, y, z] in metres, three numbers in [-0.5, 0.5]", *t));
  }
  if (const auto mm = get_number(*c, "max_residual_mm", "calibration", false)) {
    if (*mm < 1.0 || *mm > 100.0)
      error(pos_of(*c->get("max_residual_mm")), "calibration.max_residual_mm",
            with_found("expected a number in [1, 100] millimetres", *c->get("max_residual_mm")));
    else
      p.calibration.max_residual_mm = *mm;
  }
}

void Loader::read_randomization(const toml::table& root, Protocol& p) {
  const toml::table* r = sub_table(root, "randomization", "");
  if (!r) {
    if (!root.contains("randomization"))
      error({1, 1}, "randomization",
            "missing required table [randomization] with an explicit seed (it is logged with every session)");
    return;
  }
  check_keys(*r, "randomization", {"seed", "trials", "per_participant"});
  if (const auto seed = get_int(*r, "seed", "randomization", 0, std::numeric_limits<std::int64_t>::max(), true))
    p.seed = static_cast<std::uint64_t>(*seed);
  const auto mode = get_enum(*r, "trials", "randomization", {"none", "shuffle", "shuffle_within_repetition"});
  default_randomize_ = parse_mode(mode.value_or("shuffle"));
  p.seed_per_participant = get_bool(*r, "per_participant", "randomization").value_or(true);
}

RandomizeMode Loader::parse_mode(const std::string& m) {
  if (m == "none") return RandomizeMode::none;
  if (m == "shuffle_within_repetition") return RandomizeMode::shuffle_within_repetition;
  return RandomizeMode::shuffle;
}

Result<Protocol> load_protocol_text(std::string_view text, const std::string& file) {
  Loader loader(file);
  try {
    return loader.run(text);
  } catch (const std::exception& e) {
    // Only allocation failure can get here; report it rather than crash.
    return load_failure(Error::Kind::bad_input,
                        {{file, {}, "", std::string("internal failure while loading: ") + e.what()}});
  }
}

Result<Protocol> load_protocol_file(const std::string& path) {
  // A folder opens as a stream that reads nothing; say what it is instead of
  // reporting an empty protocol.
  if (std::error_code ec; std::filesystem::is_directory(path, ec))
    return load_failure(Error::Kind::bad_input, {{path, {}, "", "is a folder, not a protocol file"}});
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    std::error_code ec;
    const auto kind = std::filesystem::exists(path, ec) ? Error::Kind::io : Error::Kind::not_found;
    return load_failure(kind, {{path, {}, "", "cannot open the file for reading"}});
  }
  std::string text;
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxFileBytes)
      return load_failure(Error::Kind::bad_input,
                          {{path, {}, "", "the file is larger than 1 MiB; a protocol is a short text file"}});
  }
  if (in.bad()) return load_failure(Error::Kind::io, {{path, {}, "", "cannot read the file"}});
  return load_protocol_text(text, path);
}

const std::vector<std::string>& response_key_names() { return key_names(); }
const std::vector<std::string>& response_button_names() { return button_names(); }

}  // namespace curvlab::harness::protocol
