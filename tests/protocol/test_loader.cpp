// Loading and validation as an author meets it: every shipped protocol loads,
// every malformed one is rejected at the stated line, column and field, and
// the CLI exits with 2 without writing anything.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/loader.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <sys/wait.h>

namespace fs = std::filesystem;
using namespace curvlab::harness::protocol;

namespace {

// Every problem a load reported; none when the protocol loaded.
const std::vector<Diagnostic>& problems(const curvlab::harness::Result<Protocol>& r) {
  static const std::vector<Diagnostic> none;
  return r ? none : r.error().diagnostics;
}

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().extension() == ".toml") out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

struct CommandResult {
  int exit_code = -1;
  std::string output;
};

// Runs a shell command in `cwd`, capturing stdout and stderr together.
CommandResult run_in(const fs::path& cwd, const std::string& command) {
  const std::string full = "cd '" + cwd.string() + "' && " + command + " 2>&1";
  CommandResult r;
  FILE* pipe = popen(full.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf{};
  std::size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.output.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

struct Expectation {
  int line = 0, column = 0;
  std::string field;
};

Expectation read_expectation(const fs::path& file) {
  std::ifstream in(file);
  std::string first;
  std::getline(in, first);
  static const std::regex re(R"(^# expect: (\d+):(\d+) (\S+)\s*$)");
  std::smatch m;
  Expectation e;
  if (std::regex_match(first, m, re)) {
    e.line = std::stoi(m[1]);
    e.column = std::stoi(m[2]);
    e.field = m[3];
  }
  return e;
}

const fs::path kSource = CURVLAB_SOURCE_DIR;

}  // namespace

TEST(ProtocolFiles, EveryShippedProtocolValidatesAndExpands) {
  const auto files = files_in(kSource / "protocols");
  ASSERT_GE(files.size(), 5u);
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    const auto r = load_protocol_file(f.string());
    for (const auto& d : problems(r)) ADD_FAILURE() << format_diagnostic(d);
    ASSERT_TRUE(r.has_value());
    for (std::uint64_t participant = 1; participant <= 3; ++participant) {
      const auto d = expand_design(*r, participant);
      EXPECT_FALSE(d.trials.empty());
      for (const auto& t : d.trials) EXPECT_GT(t.derived.radius_m, 0.0);
    }
  }
}

TEST(ProtocolFiles, DemoIsShort) {
  const auto r = load_protocol_file((kSource / "protocols/demo.toml").string());
  ASSERT_TRUE(r.has_value());
  const auto d = expand_design(*r, 1);
  EXPECT_LE(d.trials.size(), 12u);
  EXPECT_LT(d.estimated_duration_ms(), 30000);
}

TEST(MalformedCorpus, EachFileYieldsItsExpectedDiagnostic) {
  const auto files = files_in(kSource / "tests/protocol/malformed");
  ASSERT_GE(files.size(), 20u);
  for (const auto& f : files) {
    SCOPED_TRACE(f.filename().string());
    const Expectation want = read_expectation(f);
    ASSERT_GT(want.line, 0) << "first line must be '# expect: LINE:COLUMN FIELD'";
    const auto r = load_protocol_file(f.string());
    EXPECT_FALSE(r.has_value());
    ASSERT_FALSE(problems(r).empty());
    bool found = false;
    for (const auto& d : problems(r)) {
      EXPECT_GT(d.pos.line, 0) << format_diagnostic(d);
      EXPECT_EQ(d.file, f.string());
      if (d.pos.line == want.line && d.pos.column == want.column && d.field == want.field) found = true;
    }
    std::string all;
    for (const auto& d : problems(r)) all += format_diagnostic(d) + "\n";
    EXPECT_TRUE(found) << "expected " << want.line << ":" << want.column << " " << want.field
                       << ", got:\n" << all;
  }
}

TEST(MalformedCorpus, CliExitsWithTwoPrintsFileLineColumnAndWritesNothing) {
  const fs::path scratch = fs::temp_directory_path() / ("curvlab-validate-" + std::to_string(::getpid()));
  fs::create_directories(scratch);
  const auto corpus = kSource / "tests/protocol/malformed";
  const auto before = fs::last_write_time(corpus);
  for (const auto& f : files_in(corpus)) {
    SCOPED_TRACE(f.filename().string());
    const Expectation want = read_expectation(f);
    const auto r = run_in(scratch, std::string(CURVLAB_CLI) + " validate '" + f.string() + "'");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    const std::string line = f.string() + ":" + std::to_string(want.line) + ":" +
                             std::to_string(want.column) + ": error: " + want.field + ": ";
    EXPECT_NE(r.output.find(line), std::string::npos) << "missing '" << line << "' in:\n" << r.output;
  }
  EXPECT_TRUE(fs::is_empty(scratch)) << "validate wrote into its working directory";
  EXPECT_EQ(fs::last_write_time(corpus), before);
  fs::remove_all(scratch);
}

TEST(Cli, ValidateOkPrintsTrialCountsAndDuration) {
  const auto r = run_in(kSource, std::string(CURVLAB_CLI) + " validate protocols/demo.toml");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("OK protocols/demo.toml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("total 8 trials"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("estimated duration"), std::string::npos) << r.output;
}

TEST(Cli, DesignJsonListsEveryTrialWithItsSeed) {
  const auto r = run_in(kSource, std::string(CURVLAB_CLI) + " design protocols/demo.toml --participant 4 --json");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("\"participant\": 4"), std::string::npos);
  EXPECT_NE(r.output.find("\"index\": 7"), std::string::npos);
  EXPECT_EQ(r.output.find("\"index\": 8"), std::string::npos);
  const auto bad = run_in(kSource, std::string(CURVLAB_CLI) + " design protocols/demo.toml --participant 0");
  EXPECT_EQ(bad.exit_code, 2);
  const auto missing = run_in(kSource, std::string(CURVLAB_CLI) + " validate no/such/file.toml");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.output.find("no/such/file.toml: error: cannot open"), std::string::npos) << missing.output;
}

TEST(Diagnostics, UnknownKeySuggestsTheClosestAndListsAllowed) {
  const auto r = load_protocol_file((kSource / "tests/protocol/malformed/unknown_key.toml").string());
  ASSERT_EQ(problems(r).size(), 1u);
  EXPECT_NE(problems(r)[0].message.find("did you mean \"projection\""), std::string::npos);
  EXPECT_NE(problems(r)[0].message.find("\"ipd_m\""), std::string::npos);
}

TEST(Diagnostics, UnknownEnumListsEveryAllowedValue) {
  const auto r = load_protocol_file((kSource / "tests/protocol/malformed/unknown_enum.toml").string());
  ASSERT_FALSE(problems(r).empty());
  const auto& m = problems(r)[0].message;
  for (const char* v : {"\"choice\"", "\"adjustment\"", "\"staircase\""}) EXPECT_NE(m.find(v), std::string::npos) << m;
}

TEST(Diagnostics, AllProblemsAreReportedInOnePass) {
  const std::string text = R"(
[protocol]
name = "x"
version = "1"
[randomization]
seed = 1
[viewing]
ipd_m = 63
eyse = "both"
[timeline]
iti_ms = -5
[judgement]
type = "choice"
options = [{ value = "a", keys = ["1"] }, { value = "b", keys = ["2"] }]
)";
  const auto r = load_protocol_text(text, "inline.toml");
  ASSERT_EQ(problems(r).size(), 3u);
  std::set<std::string> fields;
  for (const auto& d : problems(r)) fields.insert(d.field);
  EXPECT_EQ(fields, (std::set<std::string>{"viewing.eyse", "viewing.ipd_m", "timeline.iti_ms"}));
}

TEST(Diagnostics, AFailureIsOneErrorCarryingEveryProblem) {
  using Kind = curvlab::harness::Error::Kind;
  const auto missing = load_protocol_file("no/such/file.toml");
  ASSERT_FALSE(missing.has_value());
  EXPECT_EQ(missing.error().kind, Kind::not_found);
  ASSERT_EQ(problems(missing).size(), 1u);
  EXPECT_EQ(format_diagnostic(problems(missing)[0]), "no/such/file.toml: error: cannot open the file for reading");
  const auto bad = load_protocol_text("[protocol]\nname = \"x\"\nversion = 1\n[viewing]\neyse = \"both\"\n",
                                      "inline.toml");
  ASSERT_FALSE(bad.has_value());
  EXPECT_EQ(bad.error().kind, Kind::bad_input);
  ASSERT_GE(problems(bad).size(), 2u);
  EXPECT_EQ(bad.error().message, format_diagnostic(problems(bad)[0]) + " (and " +
                                     std::to_string(problems(bad).size() - 1) + " more)");
}

TEST(ProtocolFiles, ALoadedProtocolKeepsItsText) {
  const auto path = kSource / "protocols/demo.toml";
  const auto r = load_protocol_file(path.string());
  ASSERT_TRUE(r.has_value());
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  EXPECT_EQ(r->text, text.str());
  EXPECT_EQ(r->file, path.string());
}

TEST(Diagnostics, MsaaTakesTheSampleCountsOrAutoAndDefaultsToAuto) {
  const std::string head = "[protocol]\nname = \"x\"\nversion = \"1\"\n[randomization]\nseed = 1\n";
  const std::string tail = "[judgement]\ntype = \"choice\"\n"
                           "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";
  const auto bad = load_protocol_text(head + "[viewing]\nmsaa = 3\n" + tail, "inline.toml");
  ASSERT_EQ(problems(bad).size(), 1u);
  EXPECT_EQ(problems(bad)[0].field, "viewing.msaa");
  EXPECT_NE(problems(bad)[0].message.find("expected one of 1, 2, 4, 8, found 3"), std::string::npos)
      << problems(bad)[0].message;
  const auto word = load_protocol_text(head + "[viewing]\nmsaa = \"four\"\n" + tail, "inline.toml");
  ASSERT_EQ(problems(word).size(), 1u);
  EXPECT_NE(problems(word)[0].message.find("expected \"auto\" or one of 1, 2, 4, 8, found \"four\""),
            std::string::npos)
      << problems(word)[0].message;
  const auto eight = load_protocol_text(head + "[viewing]\nmsaa = 8\n" + tail, "inline.toml");
  ASSERT_TRUE(eight.has_value());
  EXPECT_EQ(eight->session_settings().viewing.msaa, 8u);
  // "auto" and no value at all: the renderer picks for its device.
  const auto automatic = load_protocol_text(head + "[viewing]\nmsaa = \"auto\"\n" + tail, "inline.toml");
  ASSERT_TRUE(automatic.has_value());
  EXPECT_FALSE(automatic->session_settings().viewing.msaa.has_value());
  const auto unset = load_protocol_text(head + tail, "inline.toml");
  ASSERT_TRUE(unset.has_value());
  EXPECT_FALSE(unset->session_settings().viewing.msaa.has_value());
}

// [calibration]: the table is calibrated before the session, with the
// tip offset and residual limit written; without the section nothing is.
TEST(Diagnostics, CalibrationSectionIsReadAndChecked) {
  const std::string head = "[protocol]\nname = \"x\"\nversion = \"1\"\n[randomization]\nseed = 1\n";
  const std::string tail = "[judgement]\ntype = \"choice\"\n"
                           "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";
  const auto unset = load_protocol_text(head + tail, "inline.toml");
  ASSERT_TRUE(unset.has_value());
  EXPECT_FALSE(unset->calibration.at_start);
  EXPECT_EQ(unset->calibration.max_residual_mm, 15.0);
  const auto set = load_protocol_text(
      head + "[calibration]\nat_start = true\ntip_offset_m = [0.0, -0.01, -0.06]\nmax_residual_mm = 10\n" + tail,
      "inline.toml");
  ASSERT_TRUE(set.has_value()) << set.error().message;
  EXPECT_TRUE(set->calibration.at_start);
  EXPECT_EQ(set->calibration.tip_offset_m, (std::array<double, 3>{0.0, -0.01, -0.06}));
  EXPECT_EQ(set->calibration.max_residual_mm, 10.0);
  const auto bad = load_protocol_text(
      head + "[calibration]\nat_start = \"yes\"\nmax_residual_mm = 0.5\ntip_offset_m = [0, 0, 2]\n" + tail,
      "inline.toml");
  std::set<std::string> fields;
  for (const auto& d : problems(bad)) fields.insert(d.field);
  EXPECT_EQ(fields, (std::set<std::string>{"calibration.at_start", "calibration.max_residual_mm",
                                           "calibration.tip_offset_m"}));
}

// [lsl]: outlets on or off (default off); anything else is named.
TEST(Diagnostics, LslSectionIsReadAndChecked) {
  const std::string head = "[protocol]\nname = \"x\"\nversion = \"1\"\n[randomization]\nseed = 1\n";
  const std::string tail = "[judgement]\ntype = \"choice\"\n"
                           "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";
  const auto unset = load_protocol_text(head + tail, "inline.toml");
  ASSERT_TRUE(unset.has_value());
  EXPECT_FALSE(unset->lsl_outlets);
  const auto set = load_protocol_text(head + "[lsl]\noutlets = true\n" + tail, "inline.toml");
  ASSERT_TRUE(set.has_value()) << set.error().message;
  EXPECT_TRUE(set->lsl_outlets);
  const auto bad = load_protocol_text(head + "[lsl]\noutlets = \"yes\"\noutlet = true\n" + tail, "inline.toml");
  std::set<std::string> fields;
  for (const auto& d : problems(bad)) fields.insert(d.field);
  EXPECT_EQ(fields, (std::set<std::string>{"lsl.outlets", "lsl.outlet"}));
}

TEST(Diagnostics, GarbageNeverCrashes) {
  for (const std::string& text : {std::string(), std::string("\0\0\0", 3), std::string("[[[[["),
                                 std::string("a = [") + std::string(5000, '['), std::string("x = 1e999"),
                                 std::string("[protocol]\nname = 5\n"), std::string("blocks = 3\nfactors = []\n")}) {
    const auto r = load_protocol_text(text, "garbage.toml");
    EXPECT_FALSE(r.has_value());
    EXPECT_FALSE(problems(r).empty());
  }
}

TEST(Diagnostics, NonAsciiTextInValueStringsIsAccepted) {
  // Instructions in any language: only keys and bare text must be ASCII.
  const std::string text =
      "[protocol]\nname = \"d\u00e9mo\"\nversion = \"1\"\n"
      "description = \"\"\"ρ = L / s, \u00a7 7,\n\u00a7 again\"\"\"\n"
      "[randomization]\nseed = 3\n"
      "[instructions]\nstart = [\"Bitte drücken Sie die Taste — ¿listo? 「はい」\"]  # ρ ≠ 1\n"
      "[judgement]\ntype = \"choice\"\noptions = [{ value = \"a\", label = \"gewölbt\", keys = [\"1\"] },"
      " { value = \"b\", label = \"gerade\", keys = [\"2\"] }]\n";
  const auto r = load_protocol_text(text, "unicode.toml");
  for (const auto& d : problems(r)) ADD_FAILURE() << format_diagnostic(d);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->instructions_start.at(0), "Bitte drücken Sie die Taste — ¿listo? 「はい」");
  EXPECT_EQ(r->judgement.options.at(0).label, "gewölbt");
}

namespace {

const std::string kHead = "[protocol]\nname = \"x\"\nversion = \"1\"\n[randomization]\nseed = 1\n";
const std::string kChoice = "[judgement]\ntype = \"choice\"\n"
                            "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";

// The one diagnostic of a text, "field: message"; a failure when it has
// none or more than one.
std::string only_problem(const std::string& text) {
  const auto r = load_protocol_text(text, "inline.toml");
  std::string all;
  for (const auto& d : problems(r)) all += format_diagnostic(d) + "\n";
  EXPECT_EQ(problems(r).size(), 1u) << all;
  return problems(r).empty() ? "" : problems(r)[0].field + ": " + problems(r)[0].message;
}

}  // namespace

TEST(Diagnostics, AMisspeltLevelGetsASuggestionAndNoSecondErrorWhereABlockNamesIt) {
  const auto r = load_protocol_file((kSource / "tests/protocol/malformed/misspelt_level_value.toml").string());
  ASSERT_EQ(problems(r).size(), 1u) << r.error().message;
  EXPECT_EQ(problems(r)[0].field, "factors.view.levels[2]");
  EXPECT_EQ(problems(r)[0].message,
            "unknown value \"natve\"; did you mean \"native\"? Expected one of \"tourist\", \"native\", "
            "\"monocular\" (levels of viewing.preset)");
}

TEST(Diagnostics, MisspeltValuesEverywhereGetASuggestion) {
  const std::string stair = "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\n"
                            "options = [{ value = \"convex\", keys = [\"1\"] }, "
                            "{ value = \"concave\", keys = [\"2\"] }]\n"
                            "staircases = [{ name = \"s\", start = 0, min = -0.1, max = 0.1, step_sizes = [0.01] }]\n";
  EXPECT_EQ(only_problem(kHead + "[viewing]\npreset = \"natve\"\n" + kChoice),
            "viewing.preset: unknown value \"natve\"; did you mean \"native\"? Expected one of \"tourist\", "
            "\"native\", \"monocular\"");
  EXPECT_EQ(only_problem(kHead + "[space]\nradius_m = \"from_tabel\"\n" + kChoice),
            "space.radius_m: expected a number of metres in [0.01, 1000] or \"from_table\", found \"from_tabel\"; "
            "did you mean \"from_table\"?");
  EXPECT_EQ(only_problem(kHead + stair + "positive = \"convx\"\n"),
            "judgement.positive: \"convx\" is not an option value; did you mean \"convex\"? Expected one of "
            "\"convex\", \"concave\"");
  EXPECT_EQ(only_problem(kHead + "[factors.space]\nsets = \"space.kind\"\nlevels = [\"E3\", \"H3\"]\n" + kChoice +
                         "[[blocks]]\nname = \"one\"\nlevels = { space = \"E4\" }\n"),
            "blocks[1].levels.space: unknown level \"E4\"; did you mean \"E3\"? Expected one of \"E3\", \"H3\"");
  EXPECT_EQ(only_problem(kHead + kChoice + "[[blocks]]\nname = \"near\"\n[[blocks]]\nname = \"far\"\n"
                         "[counterbalance]\nblocks = \"latin_square\"\n"
                         "square = [[\"near\", \"farr\"], [\"far\", \"near\"]]\n"),
            "counterbalance.square[1][2]: unknown block \"farr\"; did you mean \"far\"? "
            "Expected one of \"near\", \"far\"");
  // Nothing close: the list alone.
  EXPECT_EQ(only_problem(kHead + "[space]\nkind = \"flat\"\n" + kChoice),
            "space.kind: unknown value \"flat\": expected one of \"S3\", \"E3\", \"H3\"");
}

TEST(Diagnostics, RangeMessagesGiveTheValuesFound) {
  const std::string stair_head = "[judgement]\ntype = \"staircase\"\nparameter = \"stimulus.stick_sagitta_m\"\n"
                                 "positive = \"a\"\n"
                                 "options = [{ value = \"a\", keys = [\"1\"] }, { value = \"b\", keys = [\"2\"] }]\n";
  const auto stair = [&](const std::string& fields) {
    return kHead + stair_head + "staircases = [{ name = \"s\", step_sizes = [0.01], " + fields + " }]\n";
  };
  EXPECT_EQ(only_problem(stair("start = 0.2, min = 0.01, max = 0.05")),
            "judgement.staircases[1].start: expected 0.01 ≤ start ≤ 0.05, got 0.2");
  // An empty range is reported once, not again for its start.
  EXPECT_EQ(only_problem(stair("start = 0.2, min = 0.05, max = 0.01")),
            "judgement.staircases[1]: expected min < max, got min = 0.05, max = 0.01");
  EXPECT_EQ(only_problem(stair("start = 0, min = -2, max = 0.01")),
            "judgement.staircases[1]: expected -1 ≤ min < max ≤ 1 (stimulus.stick_sagitta_m's range), "
            "got min = -2, max = 0.01");
  EXPECT_EQ(only_problem(stair("start = 0, min = -0.1, max = 0.1, stop_reversals = 4, discard_reversals = 6")),
            "judgement.staircases[1].discard_reversals: expected discard_reversals < stop_reversals = 4, got 6 "
            "(no reversal would be left for the estimate)");
  EXPECT_EQ(only_problem(kHead + stair_head +
                         "staircases = [{ name = \"s\", start = 0, min = -0.1, max = 0.1, "
                         "step_sizes = [0.01, -0.5] }]\n"),
            "judgement.staircases[1].step_sizes[2]: expected a positive number, got -0.5");

  const auto adjust = [&](const std::string& fields) {
    return kHead + "[judgement]\ntype = \"adjustment\"\nparameter = \"stimulus.stick_sagitta_m\"\n" + fields;
  };
  EXPECT_EQ(only_problem(adjust("min = -0.05\nmax = 0.05\nstart_min = -0.1\nstart_max = 0.02\nstep = 0.01\n")),
            "judgement.start_min: expected -0.05 ≤ start_min ≤ start_max ≤ 0.05, got start_min = -0.1, "
            "start_max = 0.02");
  EXPECT_EQ(only_problem(adjust("min = -0.05\nmax = 0.05\nstart_min = 0\nstart_max = 0\nstep = 0.5\n")),
            "judgement.step: expected 0 < step ≤ max − min = 0.1, got 0.5");
  EXPECT_EQ(only_problem(adjust("min = -0.05\nmax = 0.05\nstart_min = 0\nstart_max = 0\nstep = 0.01\n"
                                "fine_step = 0.02\n")),
            "judgement.fine_step: expected 0 < fine_step ≤ step = 0.01, got 0.02");
  // A missing step is reported once: the fine step is not compared with it.
  EXPECT_EQ(only_problem(adjust("min = -0.05\nmax = 0.05\nstart_min = 0\nstart_max = 0\nfine_step = 0.02\n")),
            "judgement.step: missing required number");

  EXPECT_EQ(only_problem(kHead + "[backend]\nresolution = [8, 1024]\n" + kChoice),
            "backend.resolution: expected each size in [16, 8192] pixels, got [8, 1024]");
  EXPECT_EQ(only_problem(kHead + "[stimulus]\nstick_length_m = 0.5\nstick_sagitta_m = 0.3\n" + kChoice),
            "stimulus.stick_sagitta_m: expected |sagitta| < stick_length_m / 2 = 0.25, got 0.3");
  EXPECT_EQ(only_problem(stair("start = 0, min = -0.1, max = 0.1") + "[[blocks]]\nname = \"m\"\nrepetitions = 3\n"),
            "blocks[1].repetitions: expected 1 in a staircase block, got 3 (its length comes from the stop rule); "
            "add staircases instead");
}
