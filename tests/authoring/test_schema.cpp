// The JSON Schema that editors and taplo check protocols against must say
// exactly what the loader accepts: the committed file is what `curvlab
// schema` prints, and every section's keys, enumerations and integer ranges
// are compared with the loader's own diagnostics for a wrong key or value.
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/schema.hpp"
#include "curvlab/harness/protocol/settings.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <sys/wait.h>

namespace {

namespace pr = curvlab::harness::protocol;
using Json = nlohmann::json;

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

const Json& schema() {
  static const Json s = Json::parse(pr::protocol_json_schema());
  return s;
}

// The schema node at a JSON pointer ("/properties/space").
const Json& at(const std::string& pointer) { return schema().at(Json::json_pointer(pointer)); }

std::set<std::string> schema_keys(const std::string& pointer) {
  std::set<std::string> keys;
  const Json& node = at(pointer);
  if (node.is_array()) {
    for (const auto& k : node) keys.insert(k.get<std::string>());
  } else {
    for (const auto& [k, v] : node.at("properties").items()) keys.insert(k);
  }
  return keys;
}

// The quoted names after `marker` in the first diagnostic whose message
// contains `needle`: the loader's list of what it accepts there.
std::set<std::string> loader_list(const std::string& text, const std::string& needle, const std::string& marker) {
  const auto r = pr::load_protocol_text(text, "t.toml");
  const std::vector<pr::Diagnostic> none;
  for (const auto& d : r ? none : r.error().diagnostics) {
    if (d.message.find(needle) == std::string::npos) continue;
    const auto from = d.message.find(marker);
    if (from == std::string::npos) continue;
    std::set<std::string> names;
    std::size_t i = from + marker.size();
    while (true) {
      const auto open = d.message.find('"', i);
      if (open == std::string::npos) break;
      const auto close = d.message.find('"', open + 1);
      names.insert(d.message.substr(open + 1, close - open - 1));
      i = close + 1;
    }
    return names;
  }
  ADD_FAILURE() << "no diagnostic containing '" << needle << "' for:\n" << text;
  return {};
}

// The [lo, hi] of "expected an integer in [lo, hi]" for a value out of range.
std::pair<double, double> loader_range(const std::string& text) {
  const auto r = pr::load_protocol_text(text, "t.toml");
  const std::vector<pr::Diagnostic> none;
  for (const auto& d : r ? none : r.error().diagnostics) {
    const auto open = d.message.find("in [");
    if (open == std::string::npos) continue;
    double lo = 0.0, hi = 0.0;
    if (std::sscanf(d.message.c_str() + open, "in [%lf, %lf]", &lo, &hi) == 2) return {lo, hi};
  }
  ADD_FAILURE() << "no range diagnostic for:\n" << text;
  return {0.0, 0.0};
}

const std::string kChoice =
    "[judgement]\ntype = \"choice\"\n"
    "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";
const std::string kAdjustment =
    "[judgement]\ntype = \"adjustment\"\nparameter = \"stimulus.stick_sagitta_m\"\n"
    "min = -0.1\nmax = 0.1\nstart_min = -0.05\nstart_max = 0.05\nstep = 0.01\n";
const std::string kStaircase =
    "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"a\"\n"
    "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n"
    "staircases = [{ name = \"s\", start = 0.05, step_sizes = [0.01], min = -0.1, max = 0.1 }]\n";

// A small valid protocol with extra lines in its sections.
std::string doc(const std::string& rest, const std::string& protocol_extra = "",
                const std::string& randomization_extra = "", const std::string& judgement = kChoice) {
  return "[protocol]\nname = \"t\"\nversion = \"1\"\n" + protocol_extra + "[randomization]\nseed = 1\n" +
         randomization_extra + judgement + rest;
}

// "[section]\nkey<rest>" and the schema pointer of section.key (appends, not
// operator+ on a literal: GCC 12 warns falsely about the latter, -Wrestrict).
struct SettingDoc {
  std::string text, pointer;
};
SettingDoc setting_doc(std::string_view path, const std::string& rest) {
  const auto dot = path.find('.');
  std::string section(path.substr(0, dot)), key(path.substr(dot + 1));
  std::string text;
  text.append("[").append(section).append("]\n").append(key).append(rest);
  std::string pointer;
  pointer.append("/properties/").append(section).append("/properties/").append(key);
  return {doc(text), pointer};
}

TEST(Schema, CommittedFileIsWhatTheGeneratorPrints) {
  const std::string committed = read_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/schema.json");
  EXPECT_EQ(committed, pr::protocol_json_schema())
      << "protocols/schema.json is stale: run `curvlab schema --out protocols/schema.json`";
}

TEST(Schema, CurvlabSchemaPrintsTheCommittedFile) {
  const std::string cmd = std::string(CURVLAB_CLI) + " schema";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  std::array<char, 4096> buf{};
  std::size_t n = 0;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  const int status = pclose(pipe);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  EXPECT_EQ(out, read_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/schema.json"));
}

TEST(Schema, IsDraft07AndClosedAtTheTop) {
  EXPECT_EQ(schema().at("$schema"), "http://json-schema.org/draft-07/schema#");
  EXPECT_EQ(schema().at("additionalProperties"), false);
  EXPECT_EQ(schema().at("required"), Json::array({"protocol", "randomization"}));
}

struct KeysCase {
  std::string where;
  std::string text;
  std::string pointer;  // the schema's list of keys allowed there
};

TEST(Schema, EverySectionAllowsExactlyTheLoadersKeys) {
  const std::string bad = "zz_unknown = 1\n";
  std::vector<KeysCase> cases = {
      {"top level", bad + doc(""), ""},
      {"[protocol]", doc("", bad), "/properties/protocol"},
      {"[randomization]", doc("", "", bad), "/properties/randomization"},
      {"[factors.f]", doc("[factors.f]\nlevels = [\"x\"]\n" + bad), "/properties/factors/additionalProperties"},
      {"choice judgement", doc("", "", "", kChoice + bad), "/properties/judgement/allOf/0/then/propertyNames/enum"},
      {"adjustment judgement", doc("", "", "", kAdjustment + bad),
       "/properties/judgement/allOf/1/then/propertyNames/enum"},
      {"staircase judgement", doc("", "", "", kStaircase + bad),
       "/properties/judgement/allOf/2/then/propertyNames/enum"},
      {"judgement of unknown type", doc("", "", "", "[judgement]\ntype = \"zz\"\n" + bad), "/properties/judgement"},
      {"judgement option",
       doc("", "", "",
           "[judgement]\ntype = \"choice\"\noptions = [{ value = \"a\", keys = [\"1\"], zz_unknown = 1 }, "
           "{ value = \"b\", keys = [\"2\"] }]\n"),
       "/properties/judgement/properties/options/items"},
      {"staircase table",
       doc("", "", "",
           "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"a\"\n"
           "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n"
           "staircases = [{ name = \"s\", start = 0.05, step_sizes = [0.01], min = -0.1, max = 0.1, "
           "zz_unknown = 1 }]\n"),
       "/properties/judgement/properties/staircases/items"},
      {"[[blocks]]", doc("[[blocks]]\nname = \"b\"\n" + bad), "/properties/blocks/items"},
      {"block judgement", doc("[[blocks]]\nname = \"b\"\n[blocks.judgement]\ntype = \"choice\"\n"
                              "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n" +
                              bad),
       "/properties/blocks/items/properties/judgement/allOf/0/then/propertyNames/enum"},
  };
  for (const char* section : {"space", "tracking", "viewing", "timeline", "stimulus", "table", "backend",
                              "calibration", "counterbalance", "session", "instructions"}) {
    cases.push_back({std::string("[") + section + "]", doc(std::string("[") + section + "]\n" + bad),
                     std::string("/properties/") + section});
  }
  for (const char* section : {"space", "tracking", "viewing", "timeline", "stimulus", "table"}) {
    cases.push_back({std::string("[blocks.") + section + "]",
                     doc("[[blocks]]\nname = \"b\"\n[blocks." + std::string(section) + "]\n" + bad),
                     std::string("/properties/blocks/items/properties/") + section});
  }
  for (const auto& c : cases) {
    SCOPED_TRACE(c.where);
    EXPECT_EQ(schema_keys(c.pointer), loader_list(c.text, "unknown key \"zz_unknown\"", "Expected one of:"));
  }
}

TEST(Schema, EnumerationsAreTheLoadersValues) {
  struct EnumCase {
    std::string text, pointer;
  };
  const std::string v = "\"zz_bad\"\n";
  std::vector<EnumCase> cases = {
      {doc("[backend]\npreferred = " + v), "/properties/backend/properties/preferred/enum"},
      {doc("", "", "trials = " + v), "/properties/randomization/properties/trials/enum"},
      {doc("[counterbalance]\nblocks = " + v), "/properties/counterbalance/properties/blocks/enum"},
      {doc("", "", "", "[judgement]\ntype = " + v), "/properties/judgement/properties/type/enum"},
      {doc("[[blocks]]\nname = \"b\"\nrandomize = " + v), "/properties/blocks/items/properties/randomize/enum"},
  };
  for (const auto& info : pr::all_settings()) {
    if (info.kind != pr::SettingKind::enumeration) continue;
    const auto d = setting_doc(info.path, " = " + v);
    cases.push_back({d.text, d.pointer + "/enum"});
    // A factor's levels are checked the same way.
    std::string factor = "[factors.f]\nsets = \"";
    factor.append(info.path).append("\"\nlevels = [\"zz_bad\"]\n");
    cases.push_back({doc(factor), d.pointer + "/enum"});
  }
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    EXPECT_EQ(schema_keys(c.pointer), loader_list(c.text, "zz_bad", "expected one of"));
  }
}

TEST(Schema, FactorSetsNamesEverySettingAndItsLevelsFollowTheSetting) {
  const Json& factor = at("/properties/factors/additionalProperties");
  std::set<std::string> paths;
  for (const auto& info : pr::all_settings()) paths.insert(std::string(info.path));
  std::set<std::string> sets;
  for (const auto& s : factor.at("/properties/sets/enum"_json_pointer)) sets.insert(s.get<std::string>());
  EXPECT_EQ(sets, paths);
  // One if/then per setting, plus the label-only factor.
  EXPECT_EQ(factor.at("allOf").size(), paths.size() + 1);
  // A factor that varies the space may only take the space's values.
  bool found = false;
  for (const auto& rule : factor.at("allOf"))
    if (rule.at("if").contains("properties") && rule.at("/if/properties/sets/const"_json_pointer) == "space.kind") {
      EXPECT_EQ(rule.at("/then/properties/levels/items/enum"_json_pointer), Json::array({"S3", "E3", "H3"}));
      found = true;
    }
  EXPECT_TRUE(found);
}

TEST(Schema, IntegerRangesAreTheLoadersRanges) {
  struct RangeCase {
    std::string text, pointer;
  };
  const std::string big = " = 2000000000\n";
  std::vector<RangeCase> cases = {
      {doc("[backend]\nrefresh_hz" + big), "/properties/backend/properties/refresh_hz"},
      {doc("[session]\nrepetitions" + big), "/properties/session/properties/repetitions"},
      {doc("[session]\nbreak_every_trials" + big), "/properties/session/properties/break_every_trials"},
      {doc("[session]\nbreak_min_ms" + big), "/properties/session/properties/break_min_ms"},
      {doc("[[blocks]]\nname = \"b\"\nrepetitions" + big), "/properties/blocks/items/properties/repetitions"},
      {doc("[[blocks]]\nname = \"b\"\nbreak_min_ms" + big), "/properties/blocks/items/properties/break_min_ms"},
  };
  for (const char* key : {"up", "down", "stop_reversals", "max_trials", "discard_reversals"})
    cases.push_back({doc("", "", "",
                         "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\n"
                         "positive = \"a\"\noptions = [{ value = \"a\", keys = [\"1\"] }, "
                         "{ value = \"b\", keys = [\"2\"] }]\nstaircases = [{ name = \"s\", start = 0.05, "
                         "step_sizes = [0.01], min = -0.1, max = 0.1, " +
                             std::string(key) + " = 2000000000 }]\n"),
                     "/properties/judgement/properties/staircases/items/properties/" + std::string(key)});
  for (const auto& info : pr::all_settings()) {
    const auto d = setting_doc(info.path, big);
    if (info.kind == pr::SettingKind::integer || info.kind == pr::SettingKind::number)
      cases.push_back({d.text, d.pointer});
    else if (info.kind == pr::SettingKind::integer_or_auto)  // a count, or "auto"
      cases.push_back({d.text, d.pointer + "/anyOf/0"});
  }
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    const auto [lo, hi] = loader_range(c.text);
    EXPECT_EQ(at(c.pointer).at("minimum").get<double>(), lo);
    EXPECT_EQ(at(c.pointer).at("maximum").get<double>(), hi);
  }
}

TEST(Schema, ResponseNamesAreTheLoadersNames) {
  const auto names = [](const Json& a) {
    std::vector<std::string> out;
    for (const auto& s : a) out.push_back(s.get<std::string>());
    return out;
  };
  const Json& option = at("/properties/judgement/properties/options/items/properties");
  EXPECT_EQ(names(option.at("/keys/items/enum"_json_pointer)), pr::response_key_names());
  EXPECT_EQ(names(option.at("/buttons/items/enum"_json_pointer)), pr::response_button_names());
  EXPECT_EQ(std::count(pr::response_key_names().begin(), pr::response_key_names().end(), "escape"), 0)
      << "escape pauses the session";
}

TEST(Schema, EveryExampleDeclaresTheSchemaForEditors) {
  int examples = 0;
  for (const auto& e : std::filesystem::directory_iterator(std::string(CURVLAB_SOURCE_DIR) + "/protocols")) {
    if (e.path().extension() != ".toml") continue;
    ++examples;
    const std::string text = read_file(e.path().string());
    EXPECT_EQ(text.rfind("#:schema ./schema.json\n", 0), 0u) << e.path() << " must start with the directive";
  }
  EXPECT_GE(examples, 5);
}

}  // namespace
