// `curvlab validate --json` as a script meets it: one JSON document on
// stdout whatever is wrong with the file (a broken rule, a TOML syntax
// error, a file that cannot be read), exit code 2, and for a good file the
// summary it has always printed.
#include "run_cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <sys/wait.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;  // keys in the order printed

const fs::path kSource = CURVLAB_SOURCE_DIR;

struct Split {
  int exit_code = -1;
  std::string out, err;
};

// Runs `curvlab ARGS` in the source folder, stdout and stderr kept apart.
Split run_split(const std::string& args) {
  const fs::path err = fs::temp_directory_path() / ("curvlab-validate-err-" + std::to_string(::getpid()));
  const auto run = curvlab::testing::run_shell("cd '" + kSource.string() + "' && " + CURVLAB_BIN + " " + args +
                                               " 2>'" + err.string() + "'");
  Split r{run.exit_code, run.out, ""};
  std::ifstream in(err);
  std::ostringstream text;
  text << in.rdbuf();
  r.err = text.str();
  fs::remove(err);
  return r;
}

// The whole of stdout as one JSON document (parse fails on anything after it).
json document(const Split& r) {
  try {
    return json::parse(r.out);
  } catch (const json::exception& e) {
    ADD_FAILURE() << "stdout is not one JSON document (" << e.what() << "):\n" << r.out;
    return json::object();
  }
}

// Each diagnostic has exactly file, line, column, field and message.
void expect_diagnostic_shape(const json& d) {
  std::vector<std::string> keys;
  for (const auto& [k, v] : d.items()) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(keys, (std::vector<std::string>{"column", "field", "file", "line", "message"})) << d.dump();
  EXPECT_TRUE(d["message"].is_string() && !d["message"].get<std::string>().empty()) << d.dump();
}

TEST(ValidateJson, EveryMalformedFileIsOneDocumentWithItsDiagnosticAndExitTwo) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(kSource / "tests/protocol/malformed"))
    if (e.path().extension() == ".toml") files.push_back(e.path());
  ASSERT_GE(files.size(), 20u);
  static const std::regex expect(R"(^# expect: (\d+):(\d+) (\S+)\s*$)");
  for (const auto& f : files) {
    SCOPED_TRACE(f.filename().string());
    std::ifstream in(f);
    std::string first;
    std::getline(in, first);
    std::smatch m;
    ASSERT_TRUE(std::regex_match(first, m, expect));
    const Split r = run_split("validate '" + f.string() + "' --json");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const json doc = document(r);
    EXPECT_EQ(doc.at("ok"), json(false));
    EXPECT_EQ(doc.at("file"), f.string());
    ASSERT_TRUE(doc.contains("diagnostics") && doc["diagnostics"].is_array() && !doc["diagnostics"].empty());
    bool found = false;
    for (const auto& d : doc["diagnostics"]) {
      expect_diagnostic_shape(d);
      EXPECT_EQ(d["file"], f.string());
      if (d["line"] == std::stoi(m[1]) && d["column"] == std::stoi(m[2]) && d["field"] == m[3].str()) found = true;
    }
    EXPECT_TRUE(found) << "no diagnostic at " << m[1] << ":" << m[2] << " " << m[3] << " in\n" << r.out;
  }
}

TEST(ValidateJson, ASyntaxErrorIsADiagnosticWithItsPlace) {
  const Split r = run_split("validate tests/protocol/malformed/syntax_error.toml --json");
  EXPECT_EQ(r.exit_code, 2);
  const json doc = document(r);
  ASSERT_EQ(doc["diagnostics"].size(), 1u) << r.out;
  EXPECT_EQ(doc["diagnostics"][0]["field"], "syntax");
  EXPECT_GT(doc["diagnostics"][0]["line"].get<int>(), 0);
}

TEST(ValidateJson, AFileThatCannotBeReadIsOneDiagnosticWithoutAPlace) {
  for (const std::string path : {"no/such/file.toml", "tests/protocol/malformed"}) {
    SCOPED_TRACE(path);
    const Split r = run_split("validate " + path + " --json");
    EXPECT_EQ(r.exit_code, 2) << r.err;
    const json doc = document(r);
    EXPECT_EQ(doc.at("ok"), json(false));
    ASSERT_EQ(doc["diagnostics"].size(), 1u) << r.out;
    const json& d = doc["diagnostics"][0];
    expect_diagnostic_shape(d);
    EXPECT_EQ(d["file"], path);
    EXPECT_TRUE(d["line"].is_null() && d["column"].is_null() && d["field"].is_null()) << d.dump();
  }
  const json missing = document(run_split("validate no/such/file.toml --json"));
  EXPECT_EQ(missing["diagnostics"][0]["message"], "cannot open the file for reading");
  const json folder = document(run_split("validate tests/protocol/malformed --json"));
  EXPECT_EQ(folder["diagnostics"][0]["message"], "is a folder, not a protocol file");
}

TEST(ValidateJson, AGoodFileKeepsItsSummary) {
  const Split r = run_split("validate protocols/demo.toml --json");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const json doc = document(r);
  std::vector<std::string> keys;
  for (const auto& [k, v] : doc.items()) keys.push_back(k);
  EXPECT_EQ(keys, (std::vector<std::string>{"protocol", "version", "participant", "protocol_seed", "seed",
                                            "block_order", "blocks", "total_trials", "estimated_duration_s", "ok",
                                            "warnings"}));
  EXPECT_EQ(doc["ok"], true);
  EXPECT_TRUE(doc["warnings"].empty()) << doc["warnings"].dump(2);
  EXPECT_EQ(doc["total_trials"], 8);
}

}  // namespace

namespace {

TEST(ValidateBackend, AnswersTheChosenDevicesCannotGiveAreRefused) {
  // demo.toml binds its answers to keys only: fine on the desktop, refused
  // in the headset (whose controllers have no number keys).
  auto r = run_split("validate protocols/demo.toml --backend desktop");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  r = run_split("validate protocols/demo.toml --backend xr");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("'convex' (keys 1) cannot be given with --backend xr"), std::string::npos) << r.err;
  r = run_split("validate protocols/demo.toml --backend xr --json");
  EXPECT_EQ(r.exit_code, 2);
  json doc = document(r);
  EXPECT_EQ(doc["ok"], false);
  ASSERT_EQ(doc["diagnostics"].size(), 1u);
  EXPECT_EQ(doc["diagnostics"][0]["field"], "judgement");
  // proposed_study.toml binds controller buttons as well.
  EXPECT_EQ(run_split("validate protocols/proposed_study.toml --backend xr").exit_code, 0);
  EXPECT_EQ(run_split("validate protocols/demo.toml --backend vr").exit_code, 2);
}

}  // namespace

namespace {

TEST(ValidateBackend, AProtocolsResponseDevicesCountForItsAnswers) {
  // Answers bound only to HID buttons: the headset alone cannot give them;
  // with the protocol's [responses] mapping file (beside it) it can.
  const fs::path dir = fs::temp_directory_path() / ("curvlab-responses-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "box.toml") << "[[device]]\nname = \"box\"\nvendor_id = 0x1234\n"
                                     "[[device.binding]]\nresponse = \"hid_1\"\nkind = \"bit\"\nbyte = 0\nbit = 0\n"
                                     "[[device.binding]]\nresponse = \"hid_2\"\nkind = \"bit\"\nbyte = 0\nbit = 1\n";
  std::ifstream demo(kSource / "protocols" / "demo.toml");
  std::stringstream text;
  text << demo.rdbuf();
  std::string s = text.str();
  s = s.substr(0, s.find("[judgement]"));
  s += "[judgement]\ntype = \"choice\"\nprompt = \"Convex or concave?\"\noptions = [\n"
       "  { value = \"convex\", buttons = [\"hid_1\"] },\n  { value = \"concave\", buttons = [\"hid_2\"] },\n]\n";
  std::ofstream(dir / "without.toml") << s;
  std::ofstream(dir / "with.toml") << s << "\n[responses]\nhid = [\"box.toml\"]\n";
  auto r = run_split("validate '" + (dir / "without.toml").string() + "' --backend xr");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("'convex' (buttons hid_1)"), std::string::npos) << r.err;
  r = run_split("validate '" + (dir / "with.toml").string() + "' --backend xr");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::ofstream(dir / "bad.toml") << s << "\n[responses]\nhid = \"box.toml\"\n";
  r = run_split("validate '" + (dir / "bad.toml").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("responses.hid"), std::string::npos) << r.err;
  fs::remove_all(dir);
}

}  // namespace
