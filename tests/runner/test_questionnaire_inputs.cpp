// A questionnaire answered in process with each kind of control: digit
// keys, a step back with backspace to an item whose mark starts on its
// answer, the mark moved with the arrow keys and chosen with enter (the new
// answer replaces the old), and a button box's button; the reversed item
// scored mirrored.
#include "in_process.hpp"

#include <deque>

namespace {

using namespace curvlab::testing;
namespace io = curvlab::harness::io;

constexpr const char* kProtocol = R"(
[protocol]
name = "inputs"
version = "1"
[randomization]
seed = 3
[judgement]
type = "choice"
options = [{ value = "x", keys = ["1"], buttons = ["hid_1"] }, { value = "y", keys = ["2"], buttons = ["hid_2"] }]
[instruments.rating]
title = "Rate"
scale.values = [1, 2, 3, 4, 5]
scale.labels = ["low", "", "mid", "", "high"]
items = [
  { id = "first", text = "The first item." },
  { id = "second", text = "The second item." },
  { id = "third", text = "The third item.", reversed = true },
]
[[instruments.rating.subscales]]
name = "all"
items = ["first", "second", "third"]
[[blocks]]
name = "q"
kind = "questionnaire"
instrument = "rating"
)";

struct Press {
  std::string item;  // the overlay's "item k/3" the press is meant for
  io::SourceId source;
  io::Control control;
};

TEST(QuestionnaireInputs, KeysTheMarkAStepBackAndAButtonBoxAnswerAndAreStoredAsGiven) {
  auto loaded = pr::load_protocol_text(kProtocol, "inputs.toml");
  ASSERT_TRUE(loaded.has_value()) << pr::format_diagnostic(loaded.error().diagnostics[0]);
  rn::HeadlessOptions ho;
  ho.no_gpu = true;
  auto made = rn::HeadlessDevices::create(ho, rn::standing_at(rn::nominal_calibration(loaded->session_settings())));
  ASSERT_TRUE(made.has_value()) << made.error().message;
  ScriptedDevices devices(*made.value().display, *made.value().poses);
  const io::SourceId keyboard{io::SourceKind::keyboard, ""}, box{io::SourceKind::hid, "box"};
  const auto key = [](std::string name) { return io::Control{io::ControlKind::key, std::move(name)}; };
  std::deque<Press> script{
      {"item 1/3", keyboard, key("4")},
      {"item 2/3", keyboard, key("5")},
      // The participant thinks again and goes back from item 3: item 2's mark
      // starts on its answer (5), two steps left is 3, enter chooses it.
      {"item 3/3", keyboard, key("backspace")},
      {"item 2/3", keyboard, key("left")},
      {"item 2/3", keyboard, key("left")},
      {"item 2/3", keyboard, key("enter")},
      {"item 3/3", box, io::Control{io::ControlKind::button, "hid_2"}},
  };
  std::string on_screen;
  std::int64_t since_ns = -1;
  devices.shown = [&](const io::Overlay& o) {
    if (o.text != on_screen) {
      on_screen = o.text;
      since_ns = -1;
    }
  };
  devices.inputs = [&](const io::FrameTiming& t, const std::string&, std::vector<io::InputEvent>& out) {
    if (script.empty() || on_screen.find(script.front().item) == std::string::npos) return io::Signal::none;
    if (since_ns < 0) since_ns = t.now_ns;
    if (t.now_ns - since_ns < 100'000'000) return io::Signal::none;
    io::InputEvent in;
    in.t_ns = t.now_ns;
    in.source = script.front().source;
    in.control = script.front().control;
    out.push_back(in);
    script.pop_front();
    since_ns = t.now_ns;
    return io::Signal::none;
  };
  rn::RunOptions o;
  o.participant = "T01";
  o.drawing = rn::FrameDrawing::none;
  const auto db = (fresh_dir("questionnaire_inputs") / "s.sqlite").string();
  auto result = rn::run_session(*loaded, kProtocol, db, o, devices.station(), made.value().clock());
  ASSERT_TRUE(result.has_value()) << result.error().message;
  EXPECT_TRUE(script.empty()) << script.size() << " presses left, next for " << script.front().item;
  const auto answers = query(db, "SELECT item_index, item_id, value, label, device FROM questionnaire_answers "
                                 "ORDER BY item_index");
  ASSERT_EQ(answers.size(), 3u);
  EXPECT_EQ(answers[0], (std::vector<std::string>{"0", "first", "4", "", "keyboard"}));
  EXPECT_EQ(answers[1], (std::vector<std::string>{"1", "second", "3", "mid", "keyboard"}));
  EXPECT_EQ(answers[2], (std::vector<std::string>{"2", "third", "2", "", "hid:box"}));
  // Item 2 was shown twice: the step back showed it again.
  EXPECT_EQ(query(db, "SELECT count(*) FROM events WHERE kind = 'instructions' AND "
                      "json_extract(detail, '$.page') = 1")[0][0],
            "2");
  // 4 + 3 + (1 + 5 − 2) = 11.
  const auto scores = query(db, "SELECT subscale, rule, raw, score FROM questionnaire_scores");
  ASSERT_EQ(scores.size(), 1u);
  EXPECT_EQ(scores[0], (std::vector<std::string>{"all", "sum", "11.0", "11.0"}));
}

}  // namespace
