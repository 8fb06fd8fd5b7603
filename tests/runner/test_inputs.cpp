// Inputs as each response source gives them: the source stored as the
// response device, the control kept for the record, what the source means
// by it, and the answer it gives through the judgement on screen.
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/runner/calibration.hpp"
#include "curvlab/harness/runner/trial_state.hpp"
#include "curvlab/harness/xr/actions.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace {

namespace io = curvlab::harness::io;
namespace rn = curvlab::harness::runner;
namespace pr = curvlab::harness::protocol;
using io::Intent;

pr::Protocol example(const std::string& name) {
  auto loaded = pr::load_protocol_file(std::string(CURVLAB_SOURCE_DIR) + "/protocols/" + name + ".toml");
  EXPECT_TRUE(loaded.has_value());
  return *loaded;
}

// A choice answered by a button box's two buttons.
pr::Judgement button_box() {
  pr::Judgement j;
  j.type = pr::find_judgement_type("choice");
  j.options = {{"convex", "", {}, {"hid_1"}}, {"concave", "", {}, {"hid_2"}}};
  return j;
}

TEST(Inputs, EachSourceIsStoredAsBefore) {
  EXPECT_EQ(io::to_string(io::SourceId{io::SourceKind::keyboard, ""}), "keyboard");
  EXPECT_EQ(io::to_string(io::SourceId{io::SourceKind::script, ""}), "script");
  EXPECT_EQ(io::to_string(io::SourceId{io::SourceKind::observer, ""}), "observer");
  EXPECT_EQ(io::to_string(io::SourceId{io::SourceKind::hid, "button box"}), "hid:button box");
  EXPECT_EQ(io::to_string(curvlab::harness::xr::controller_input(0, true, "x", true).source), "xr:left");
  EXPECT_EQ(io::to_string(curvlab::harness::xr::controller_input(0, false, "a", true).source), "xr:right");
  EXPECT_EQ(io::to_string(curvlab::harness::devices::response_input(0, "pedals", "left", true).source), "hid:pedals");
  EXPECT_EQ(io::to_string(curvlab::harness::desktop::key_input(0, "1", true).source), "keyboard");
  EXPECT_EQ(io::to_string(curvlab::harness::desktop::key_input(0, "1", true, io::SourceKind::script).source), "script");
}

// A and the trigger are one event each: it continues a page, and answers
// where the protocol binds the button.
TEST(Inputs, TheControllersAIsOneEventThatContinuesAndAnswers) {
  const io::InputEvent a = curvlab::harness::xr::controller_input(7, false, "a", true);
  EXPECT_EQ(a.t_ns, 7);
  EXPECT_EQ(a.control, (io::Control{io::ControlKind::button, "a"}));
  EXPECT_TRUE(a.intents.has(Intent::continue_page));
  EXPECT_TRUE(a.intents.has(Intent::calibration_accept));
  EXPECT_FALSE(a.intents.has(Intent::calibration_touch));
  for (const bool left : {true, false}) {
    const io::InputEvent trigger =
        curvlab::harness::xr::controller_input(0, left, curvlab::harness::xr::protocol_button("trigger", left), true);
    EXPECT_TRUE(trigger.intents.has(Intent::continue_page));
    EXPECT_EQ(trigger.intents.has(Intent::calibration_touch), !left);  // the right hand touches
  }
  EXPECT_TRUE(curvlab::harness::xr::controller_input(0, false, "b", true).intents.has(Intent::calibration_fit_three));
  EXPECT_FALSE(curvlab::harness::xr::controller_input(0, true, "x", true).intents.has(Intent::continue_page));

  // one_eye_vs_two binds A to "straight": the one press both turns a page
  // and, in a trial, answers.
  const pr::Protocol p = example("one_eye_vs_two");
  const std::vector<std::string> continues = rn::page_continues(p);
  rn::Page page(0, 0, continues);
  page.frame(0, {});
  EXPECT_TRUE(page.frame(1, {a}));
  const pr::Judgement& j = p.blocks.at(0).judgement.type != nullptr ? p.blocks.at(0).judgement : p.judgement;
  const auto verdict = rn::classify_input(j, a, true);
  ASSERT_EQ(verdict.use, rn::InputUse::choose);
  EXPECT_EQ(j.options.at(verdict.option).value, "straight");
}

// A HID button answers through the protocol's buttons; a key of the same
// name does not, and the box's own continue button turns pages.
TEST(Inputs, AHidButtonNamedInTheMappingGivesItsAnswer) {
  const pr::Judgement j = button_box();
  const io::InputEvent second = curvlab::harness::devices::response_input(5, "box", "hid_2", true);
  EXPECT_EQ(second.control, (io::Control{io::ControlKind::button, "hid_2"}));
  EXPECT_TRUE(second.intents.empty());
  const auto verdict = rn::classify_input(j, second, true);
  EXPECT_EQ(verdict.use, rn::InputUse::choose);
  EXPECT_EQ(verdict.option, 1u);
  EXPECT_EQ(rn::classify_input(j, curvlab::harness::devices::response_input(5, "box", "hid_1", true), true).option, 0u);
  EXPECT_EQ(rn::classify_input(j, curvlab::harness::desktop::key_input(5, "hid_2", true), true).use, rn::InputUse::ignored);
  EXPECT_EQ(rn::classify_input(j, second, false).use, rn::InputUse::early);

  const io::InputEvent go = curvlab::harness::devices::response_input(0, "box", "continue", true);
  EXPECT_TRUE(go.intents.has(Intent::continue_page));
  const std::vector<std::string> none;
  rn::Page page(0, 0, none);
  page.frame(0, {});
  EXPECT_FALSE(page.frame(1, {second}));
  EXPECT_TRUE(page.frame(2, {go}));

  auto mapping = curvlab::harness::devices::parse_mapping(
      "[[device]]\nname = \"box\"\nvendor_id = 0x1234\n"
      "[[device.binding]]\nresponse = \"hid_1\"\nkind = \"bit\"\nbyte = 0\nbit = 0\n"
      "[[device.binding]]\nresponse = \"continue\"\nkind = \"bit\"\nbyte = 0\nbit = 1\n",
      "box.toml");
  ASSERT_TRUE(mapping.has_value()) << mapping.error().message;
  const io::Reach reach = curvlab::harness::devices::mapping_reach(*mapping);
  EXPECT_EQ(reach.kind, io::SourceKind::hid);
  EXPECT_TRUE(reach.intents.has(Intent::continue_page));
  EXPECT_FALSE(reach.intents.has(Intent::calibration_touch));
  EXPECT_EQ(reach.continue_phrase, "press the continue button of box");
}

// The keyboard's keys: space and enter turn pages and calibrate, F and R
// calibrate; the others only answer through the protocol's keys.
TEST(Inputs, TheKeyboardsKeysMeanWhatThePagesAndTheCalibrationAsk) {
  const io::InputEvent space = curvlab::harness::desktop::key_input(3, "space", true);
  EXPECT_EQ(space.control, (io::Control{io::ControlKind::key, "space"}));
  EXPECT_TRUE(space.intents.has(Intent::continue_page));
  EXPECT_TRUE(space.intents.has(Intent::calibration_touch));
  EXPECT_TRUE(curvlab::harness::desktop::key_input(0, "enter", true).intents.has(Intent::calibration_accept));
  EXPECT_TRUE(curvlab::harness::desktop::key_input(0, "return", true).intents.has(Intent::continue_page));
  EXPECT_TRUE(curvlab::harness::desktop::key_input(0, "1", true).intents.empty());
  EXPECT_FALSE(curvlab::harness::desktop::key_input(0, "a", true).intents.has(Intent::calibration_accept));
  const io::Reach reach = curvlab::harness::desktop::keyboard_reach();
  EXPECT_TRUE(reach.every_key);
  EXPECT_TRUE(reach.intents.has(Intent::calibration_redo));

  const pr::Protocol demo = example("demo");
  const auto verdict = rn::classify_input(demo.blocks.at(0).judgement.type != nullptr ? demo.blocks.at(0).judgement
                                                                                      : demo.judgement,
                                          curvlab::harness::desktop::key_input(0, "2", true), true);
  EXPECT_EQ(verdict.use, rn::InputUse::choose);
  EXPECT_EQ(verdict.option, 1u);
}

// The same command from each kind of source that calibrates, and none from
// those that do not.
TEST(Inputs, CalibrationCommandsComeFromEachSourceKind) {
  using Stage = rn::CalibrationStage;
  using Command = rn::CalibrationCommand;
  const io::InputEvent touches[] = {curvlab::harness::desktop::key_input(0, "space", true),
                                    curvlab::harness::desktop::key_input(0, "space", true, io::SourceKind::script),
                                    curvlab::harness::xr::controller_input(0, false, "right_trigger", true)};
  for (const auto& in : touches) EXPECT_EQ(rn::calibration_command(in, Stage::touching), Command::touch);
  const io::InputEvent accepts[] = {curvlab::harness::desktop::key_input(0, "enter", true),
                                    curvlab::harness::xr::controller_input(0, false, "a", true)};
  for (const auto& in : accepts) EXPECT_EQ(rn::calibration_command(in, Stage::fitted), Command::accept);
  const io::InputEvent fits[] = {curvlab::harness::desktop::key_input(0, "f", true),
                                 curvlab::harness::xr::controller_input(0, false, "b", true)};
  for (const auto& in : fits) EXPECT_EQ(rn::calibration_command(in, Stage::touching), Command::fit_three);
  EXPECT_FALSE(rn::calibration_command(curvlab::harness::devices::response_input(0, "box", "continue", true), Stage::touching));
  io::InputEvent observer;
  observer.source = {io::SourceKind::observer, ""};
  observer.control = {io::ControlKind::key, "space"};
  EXPECT_FALSE(rn::calibration_command(observer, Stage::touching));
}

}  // namespace

// The response panel names each answer by its label with the input that
// gives it at this station: keys at a keyboard, the box's buttons where the
// station has only the box; an answer's input and label stay together.
TEST(Inputs, TheResponsePanelShowsEachAnswerWithTheInputAtHand) {
  const std::string nb = "\u00a0";
  const pr::Protocol p = example("demo");
  io::Reach keyboard;
  keyboard.every_key = true;
  EXPECT_EQ(rn::response_panel_text(p.judgement, {keyboard}),
            p.judgement.prompt + "\n\n[1]" + nb + "convex     [2]" + nb + "straight     [3]" + nb + "concave");

  pr::Judgement box = button_box();
  box.prompt = "Which way?";
  box.options[0].label = "bowed toward me";
  io::Reach buttons;
  buttons.kind = io::SourceKind::hid;
  buttons.buttons = {"hid_1", "hid_2"};
  EXPECT_EQ(rn::response_panel_text(box, {buttons}),
            "Which way?\n\n[hid" + nb + "1]" + nb + "bowed" + nb + "toward" + nb + "me     [hid" + nb + "2]" + nb +
                "concave");
  // A source that cannot give an answer does not offer it.
  io::Reach one;
  one.buttons = {"hid_2"};
  EXPECT_EQ(rn::response_panel_text(box, {one}), "Which way?\n\n[hid" + nb + "2]" + nb + "concave");
}
