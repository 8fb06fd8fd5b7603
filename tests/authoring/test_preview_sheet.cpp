// `curvlab preview` read as an author reads its sheet: each panel's table
// gives the value its images were rendered at, the judgements' answers are
// listed with their keys and buttons, each staircase with its start, steps,
// up/down and stop rules, and practice trials have panels of their own.
// Renders (lavapipe): label vulkan.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;

// A practice block (choice) sharing its cell's settings with the main
// staircase block, two staircases, and an adjustment block with the same
// settings again.
constexpr const char* kProtocol = R"(
[protocol]
name = "sheet-check"
version = "1.0.0"

[randomization]
seed = 3

[stimulus]
stick_anchor = "head"
stick_distance_m = 0.5
show_table = false

[factors.space]
sets = "space.kind"
levels = ["E3", "H3"]

[judgement]
type = "staircase"
parameter = "stimulus.stick_sagitta_m"
positive = "convex"
options = [
  { value = "convex", label = "Toward me", keys = ["left", "1"], buttons = ["left_trigger"] },
  { value = "concave", label = "Away from me", keys = ["right"] },
]

[[judgement.staircases]]
name = "high"
start = 0.05
up = 1
down = 2
step_sizes = [0.02, 0.01]
stop_reversals = 6
max_trials = 12
discard_reversals = 2
min = -0.1
max = 0.1

[[judgement.staircases]]
name = "low"
start = -0.03
up = 1
down = 1
step_sizes = [0.01]
stop_reversals = 4
max_trials = 10
discard_reversals = 1
min = -0.1
max = 0.1

[[blocks]]
name = "warmup"
practice = true
levels = { space = "E3" }
judgement = { type = "choice", options = [
  { value = "convex", label = "Toward me", keys = ["left"] },
  { value = "concave", label = "Away from me", keys = ["right"] },
] }

[[blocks]]
name = "main"

[[blocks]]
name = "adjust"
levels = { space = "E3" }
[blocks.judgement]
type = "adjustment"
parameter = "stimulus.stick_sagitta_m"
min = -0.1
max = 0.1
start_min = -0.04
start_max = 0.04
step = 0.005
keys_decrease = ["down"]
keys_increase = ["up"]
buttons_confirm = ["a"]
)";

std::string unescape(std::string s) {
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"&quot;", "\""}, {"&lt;", "<"}, {"&gt;", ">"},
                                 {"&amp;", "&"}})
    for (auto at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size()))
      s.replace(at, from.size(), to);
  return s;
}

// The text between `open` and the next `close` after `from`, unescaped; ""
// when there is none.
std::string between(const std::string& text, const std::string& open, const std::string& close,
                    std::size_t from = 0) {
  const auto a = text.find(open, from);
  if (a == std::string::npos) return "";
  const auto b = text.find(close, a + open.size());
  return b == std::string::npos ? "" : unescape(text.substr(a + open.size(), b - a - open.size()));
}

// A table row's value: <tr><th>NAME</th><td>VALUE</td></tr>.
std::string row(const std::string& html, const std::string& name) {
  return between(html, "<tr><th>" + name + "</th><td>", "</td>");
}

struct Panel {
  std::string title, html;
};

class PreviewSheet : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(fs::temp_directory_path() / ("curvlab-preview-sheet-" + std::to_string(::getpid())));
    fs::create_directories(*dir_);
    std::ofstream(*dir_ / "check.toml") << kProtocol;
    const std::string cmd = "cd '" + dir_->string() + "' && " + CURVLAB_CLI +
                            " preview check.toml --out sheet --software --size 64x48 >preview.log 2>&1";
    const int status = std::system(cmd.c_str());
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(*dir_ / "sheet" / "index.html");
    std::ostringstream text;
    text << in.rdbuf();
    sheet_ = new std::string(text.str());
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete sheet_;
  }
  void SetUp() override {
    ASSERT_EQ(exit_code_, 0) << "curvlab preview failed; see " << (*dir_ / "preview.log");
    ASSERT_FALSE(sheet_->empty());
  }

  static std::vector<Panel> panels() {
    std::vector<Panel> out;
    for (auto at = sheet_->find("<section class=\"condition"); at != std::string::npos;
         at = sheet_->find("<section class=\"condition", at + 1)) {
      const auto end = sheet_->find("</section>", at);
      const std::string html = sheet_->substr(at, end - at);
      out.push_back({between(html, "<h3>", "</h3>"), html});
    }
    return out;
  }
  // The part of the sheet from the heading `h2` to the next heading.
  static std::string section(const std::string& h2) {
    const auto at = sheet_->find("<h2>" + h2);
    if (at == std::string::npos) return "";
    return sheet_->substr(at, sheet_->find("<h2>", at + 4) - at);
  }

  static inline fs::path* dir_ = nullptr;
  static inline std::string* sheet_ = nullptr;
  static inline int exit_code_ = -1;
};

TEST_F(PreviewSheet, EachPanelShowsTheValueItWasRenderedAt) {
  const auto all = panels();
  // warmup E3; main: E3 and H3 × high and low; adjust E3.
  ASSERT_EQ(all.size(), 6u);
  int staircase_panels = 0;
  for (const auto& p : all) {
    SCOPED_TRACE(p.title);
    const std::string stick = row(p.html, "stick");
    const std::string note = between(p.html, "Rendered with the ", ".</p>");
    if (p.title.find("staircase \"high\"") != std::string::npos) {
      EXPECT_NE(stick.find("sagitta 50 mm"), std::string::npos) << stick;
      EXPECT_NE(note.find("stimulus.stick_sagitta_m = 0.05"), std::string::npos) << note;
      ++staircase_panels;
    } else if (p.title.find("staircase \"low\"") != std::string::npos) {
      EXPECT_NE(stick.find("sagitta -30 mm"), std::string::npos) << stick;
      EXPECT_NE(note.find("stimulus.stick_sagitta_m = -0.03"), std::string::npos) << note;
      ++staircase_panels;
    } else if (!note.empty()) {
      // The adjustment block: its first trial's drawn start, in the note
      // (4 decimals, metres) and in the table (millimetres).
      const auto eq = note.find("stimulus.stick_sagitta_m = ");
      ASSERT_NE(eq, std::string::npos) << note;
      const double start_m = std::stod(note.substr(eq + 27));
      const auto at = stick.find("sagitta ");
      ASSERT_NE(at, std::string::npos) << stick;
      EXPECT_NEAR(std::stod(stick.substr(at + 8)), start_m * 1000.0, 0.06) << stick;
      EXPECT_GT(std::abs(start_m), 0.0);
    } else {
      EXPECT_NE(stick.find("sagitta 0 mm"), std::string::npos) << stick;
    }
  }
  EXPECT_EQ(staircase_panels, 4);
}

TEST_F(PreviewSheet, PracticeTrialsHaveTheirOwnPanels) {
  int practice = 0;
  for (const auto& p : panels()) {
    SCOPED_TRACE(p.title);
    const std::string trials = row(p.html, "trials per block");
    const bool is_practice = p.title.find("— practice") != std::string::npos;
    EXPECT_EQ(trials.find("warmup") != std::string::npos, is_practice) << trials;
    if (is_practice) {
      ++practice;
      EXPECT_EQ(trials, "warmup: 1");
      EXPECT_NE(p.html.find("no prediction: practice trials are not predicted"), std::string::npos);
    }
  }
  EXPECT_EQ(practice, 1);
}

TEST_F(PreviewSheet, ListsEveryAnswerWithItsKeysAndButtons) {
  const std::string responses = unescape(section("Responses and judgement settings"));
  ASSERT_FALSE(responses.empty());
  const auto block = [&](const std::string& name) {
    const auto at = responses.find("<h3>Block " + name + "</h3>");
    EXPECT_NE(at, std::string::npos) << name;
    return at == std::string::npos ? std::string() : responses.substr(at, responses.find("<h3>", at + 4) - at);
  };
  const std::string main = block("main");
  EXPECT_NE(main.find("<tr><td>convex</td><td>Toward me</td><td>left, 1</td><td>left_trigger</td></tr>"),
            std::string::npos)
      << main;
  EXPECT_NE(main.find("<tr><td>concave</td><td>Away from me</td><td>right</td><td>—</td></tr>"), std::string::npos)
      << main;
  const std::string warmup = block("warmup (practice)");
  EXPECT_NE(warmup.find("<tr><td>convex</td><td>Toward me</td><td>left</td><td>—</td></tr>"), std::string::npos)
      << warmup;
  const std::string adjust = block("adjust");
  for (const char* answer : {"<tr><td>decrease</td><td>—</td><td>down</td><td>—</td></tr>",
                             "<tr><td>increase</td><td>—</td><td>up</td><td>—</td></tr>",
                             "<tr><td>confirm</td><td>—</td><td>—</td><td>a</td></tr>"})
    EXPECT_NE(adjust.find(answer), std::string::npos) << answer << "\n" << adjust;
  EXPECT_EQ(row(adjust, "start"), "drawn for each trial from [-0.04, 0.04]");
  EXPECT_EQ(row(adjust, "step"), "0.005 per press");
}

TEST_F(PreviewSheet, ListsEachStaircaseWithItsStartStepsAndRules) {
  const std::string responses = section("Responses and judgement settings");
  const std::string high = row(responses, "staircase &quot;high&quot;");
  const std::string low = row(responses, "staircase &quot;low&quot;");
  for (const char* part : {"start 0.05", "step sizes 0.02, 0.01", "1-up/2-down", "converging on 70.7 % \"convex\"",
                           "stops after 6 reversals or 12 trials", "after the first 2", "clamped to [-0.1, 0.1]"})
    EXPECT_NE(high.find(part), std::string::npos) << part << " in " << high;
  for (const char* part : {"start -0.03", "step sizes 0.01 ", "1-up/1-down", "converging on 50.0 % \"convex\"",
                           "stops after 4 reversals or 10 trials", "after the first 1"})
    EXPECT_NE(low.find(part), std::string::npos) << part << " in " << low;
  EXPECT_EQ(row(responses, "positive answer"), "convex");
  EXPECT_EQ(row(responses, "parameter"), "stimulus.stick_sagitta_m");
}

// The sheet names the protocol by its file name: given the absolute path of
// a protocol in a home folder, it showed /home/<name>/… (a folder can name
// a person; docs/data.md, "Privacy").
TEST(PreviewPrivacy, NoFolderOfTheProtocolIsWrittenIntoTheSheet) {
  const fs::path dir = fs::temp_directory_path() / ("curvlab-preview-privacy-" + std::to_string(::getpid()));
  const fs::path home = dir / "home" / "jane-doe" / "study";
  fs::remove_all(dir);
  fs::create_directories(home);
  std::ofstream(home / "check.toml") << kProtocol;
  ASSERT_TRUE((home / "check.toml").is_absolute());
  const std::string cmd = std::string(CURVLAB_CLI) + " preview '" + (home / "check.toml").string() + "' --out '" +
                          (dir / "sheet").string() + "' --software --size 64x48 >'" + (dir / "log").string() +
                          "' 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "see " << dir / "log";
  std::ifstream in(dir / "sheet" / "index.html");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string sheet = text.str();
  ASSERT_FALSE(sheet.empty());
  EXPECT_NE(sheet.find("<td>protocol file</td><td><code>check.toml</code>"), std::string::npos);
  EXPECT_EQ(sheet.find("jane-doe"), std::string::npos);
  EXPECT_EQ(sheet.find(dir.string()), std::string::npos);
  EXPECT_EQ(sheet.find(fs::temp_directory_path().string()), std::string::npos);
  EXPECT_EQ(sheet.find("/home/"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
