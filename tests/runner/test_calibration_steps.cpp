// The table calibration's steps without a display: which input does what in
// each stage, touches collected and fitted, a refused set redone, and the
// panel text the participant reads.
#include "curvlab/harness/desktop/desktop.hpp"
#include "curvlab/harness/devices/responses.hpp"
#include "curvlab/harness/runner/calibration.hpp"
#include "curvlab/harness/xr/actions.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace {

namespace rn = curvlab::harness::runner;
using curvlab::geometry::PhysicalTableFit;
using curvlab::geometry::Vec3;
using Command = rn::CalibrationCommand;
using Stage = rn::CalibrationStage;

PhysicalTableFit table() {
  PhysicalTableFit t;
  t.centre_m = {0.1, -0.2};
  t.yaw_rad = 0.3;
  t.edge_m = 0.9;
  t.height_m = 0.76;
  return t;
}

Vec3 corner(int j) { return curvlab::geometry::physical_table_corner(table(), j); }

// An input as the source stored as `device` gives it: a controller
// ("xr:left", "xr:right"), a HID device ("hid:NAME"), the key script
// ("script") or the keyboard.
curvlab::harness::io::InputEvent press(std::string name, std::string device, bool pressed = true) {
  namespace io = curvlab::harness::io;
  if (device.rfind("xr:", 0) == 0)
    return curvlab::harness::xr::controller_input(0, device == "xr:left", std::move(name), pressed);
  if (device.rfind("hid:", 0) == 0) return curvlab::harness::devices::response_input(0, device.substr(4), std::move(name), pressed);
  return curvlab::harness::desktop::key_input(0, std::move(name), pressed,
                                     device == "script" ? io::SourceKind::script : io::SourceKind::keyboard);
}

TEST(CalibrationSteps, ControllerAndKeyboardInputsMeanTheSameSteps) {
  const auto cmd = [](const char* name, const char* device, Stage stage) {
    return rn::calibration_command(press(name, device), stage);
  };
  EXPECT_EQ(cmd("right_trigger", "xr:right", Stage::touching), Command::touch);
  EXPECT_EQ(cmd("space", "keyboard", Stage::touching), Command::touch);
  EXPECT_EQ(cmd("space", "script", Stage::touching), Command::touch);
  EXPECT_EQ(cmd("b", "xr:right", Stage::touching), Command::fit_three);
  EXPECT_EQ(cmd("f", "keyboard", Stage::touching), Command::fit_three);
  EXPECT_EQ(cmd("a", "xr:right", Stage::fitted), Command::accept);
  EXPECT_EQ(cmd("enter", "keyboard", Stage::fitted), Command::accept);
  EXPECT_EQ(cmd("b", "xr:right", Stage::fitted), Command::redo);
  EXPECT_EQ(cmd("r", "keyboard", Stage::fitted), Command::redo);
  EXPECT_EQ(cmd("right_trigger", "xr:right", Stage::refused), Command::redo);
  EXPECT_EQ(cmd("space", "keyboard", Stage::refused), Command::redo);
  // The keyboard's A walks left and the left trigger is the other hand: neither touches or accepts.
  EXPECT_FALSE(cmd("a", "keyboard", Stage::fitted));
  EXPECT_FALSE(cmd("left_trigger", "xr:left", Stage::touching));
  EXPECT_FALSE(cmd("continue", "xr:right", Stage::touching));
  EXPECT_FALSE(cmd("right_trigger", "xr:right", Stage::fitted));  // a second pull does not keep a fit unseen
  EXPECT_FALSE(rn::calibration_command(press("space", "keyboard", false), Stage::touching));  // a release
}

// What a source means by a control, not its name, gives the command: the
// same name from another kind of source means nothing to the calibration.
TEST(CalibrationSteps, OnlyTheSourcesThatCalibrateGiveCommands) {
  const auto cmd = [](const char* name, const char* device, Stage stage) {
    return rn::calibration_command(press(name, device), stage);
  };
  EXPECT_EQ(cmd("r", "script", Stage::refused), Command::redo);
  EXPECT_EQ(cmd("b", "xr:left", Stage::refused), Command::redo);
  EXPECT_FALSE(cmd("right_trigger", "keyboard", Stage::touching));
  EXPECT_FALSE(cmd("space", "xr:right", Stage::touching));
  EXPECT_FALSE(cmd("enter", "hid:box", Stage::fitted));
  EXPECT_FALSE(cmd("continue", "hid:box", Stage::touching));
  for (const char* device : {"keyboard", "script", "xr:left", "xr:right", "hid:box"})
    EXPECT_EQ(curvlab::harness::io::to_string(press("a", device).source), device);
}

// The text names the controls of the sources at hand that can calibrate.
TEST(CalibrationSteps, TheControlsAtHandAreThoseThatCanTouch) {
  namespace io = curvlab::harness::io;
  const auto keyboard = curvlab::harness::desktop::keyboard_reach();
  io::Reach observer;
  observer.kind = io::SourceKind::observer;
  observer.simulated = true;
  io::Reach box;
  box.kind = io::SourceKind::hid;
  box.buttons = {"right_trigger", "continue"};
  box.intents = {io::Intent::continue_page};
  const auto only_keys = rn::calibration_controls({keyboard, observer, box});
  EXPECT_TRUE(only_keys.keyboard);
  EXPECT_FALSE(only_keys.controller);
  io::Reach controllers;
  controllers.kind = io::SourceKind::xr_controller;
  controllers.intents = curvlab::harness::xr::controller_intents("right_trigger");
  const auto both = rn::calibration_controls({controllers, keyboard});
  EXPECT_TRUE(both.keyboard);
  EXPECT_TRUE(both.controller);
  EXPECT_FALSE(rn::calibration_controls({box}).controller);
}

TEST(CalibrationSteps, FourTouchesAreFittedAndAcceptedWithTheirResiduals) {
  rn::CalibrationSteps steps;
  for (int j = 0; j < 4; ++j) {
    EXPECT_EQ(steps.stage(), Stage::touching);
    EXPECT_EQ(steps.next_corner(), j);
    EXPECT_TRUE(steps.apply(Command::touch, corner(j) + Vec3(0.0, j == 2 ? 0.004 : 0.0, 0.0)));
  }
  ASSERT_EQ(steps.stage(), Stage::fitted);
  ASSERT_TRUE(steps.fit());
  EXPECT_NEAR(steps.fit()->edge_m, 0.9, 1e-9);
  EXPECT_NEAR(steps.fit()->corner_residual_m[2], 0.003, 1e-9);  // 4 mm high, the mean height 1 mm up
  EXPECT_FALSE(steps.apply(Command::touch, corner(0)));  // no fifth corner
  EXPECT_TRUE(steps.apply(Command::accept, std::nullopt));
  EXPECT_EQ(steps.stage(), Stage::accepted);
  EXPECT_EQ(steps.touches().size(), 4u);
}

TEST(CalibrationSteps, ThreeCornersAreFittedOnlyWhenAsked) {
  rn::CalibrationSteps steps;
  EXPECT_FALSE(steps.apply(Command::fit_three, std::nullopt));  // nothing touched yet
  for (int j = 0; j < 3; ++j) steps.apply(Command::touch, corner(j));
  EXPECT_EQ(steps.stage(), Stage::touching);
  EXPECT_TRUE(steps.apply(Command::fit_three, std::nullopt));
  ASSERT_EQ(steps.stage(), Stage::fitted);
  EXPECT_EQ(steps.fit()->corners_used, 3);
}

TEST(CalibrationSteps, ARefusedSetIsShownWithItsReasonAndTouchedAgain) {
  rn::CalibrationSteps steps;
  for (int j = 0; j < 4; ++j) steps.apply(Command::touch, corner(j) + Vec3(j == 1 ? 0.03 : 0.0, 0.0, 0.0));
  ASSERT_EQ(steps.stage(), Stage::refused);
  EXPECT_NE(steps.refusal().find("touch 2 (front-right)"), std::string::npos) << steps.refusal();
  EXPECT_FALSE(steps.fit());
  EXPECT_FALSE(steps.apply(Command::accept, std::nullopt));  // a refused fit cannot be kept
  EXPECT_TRUE(steps.apply(Command::redo, std::nullopt));
  EXPECT_EQ(steps.stage(), Stage::touching);
  EXPECT_TRUE(steps.touches().empty());
  EXPECT_EQ(steps.redone(), 1);
  ASSERT_EQ(steps.refusals().size(), 1u);
  // The limit is the one given: 40 mm lets the same set through.
  curvlab::geometry::CalibrationLimits loose;
  loose.max_residual_m = 0.040;
  rn::CalibrationSteps lenient(loose);
  for (int j = 0; j < 4; ++j) lenient.apply(Command::touch, corner(j) + Vec3(j == 1 ? 0.03 : 0.0, 0.0, 0.0));
  EXPECT_EQ(lenient.stage(), Stage::fitted);
}

TEST(CalibrationSteps, AnUntrackedControllerTakesNoTouchAndSaysSo) {
  rn::CalibrationSteps steps;
  EXPECT_TRUE(steps.apply(Command::touch, std::nullopt));
  EXPECT_TRUE(steps.touches().empty());
  EXPECT_NE(steps.note().find("not tracked"), std::string::npos);
  steps.apply(Command::touch, corner(0));
  EXPECT_TRUE(steps.note().empty());
  EXPECT_EQ(steps.touches().size(), 1u);
}

// One line of the panel without its wrapping.
std::string unwrapped(std::string text) {
  for (char& c : text)
    if (c == '\n') c = ' ';
  return text;
}

TEST(CalibrationSteps, ThePanelNamesTheCornerAndTheInputsAtHand) {
  const rn::CalibrationControls headset{true, false}, desk{false, true};
  rn::CalibrationSteps steps;
  EXPECT_NE(unwrapped(rn::calibration_text(steps, headset))
                .find("Touch the front-left corner with the right controller and pull the trigger."),
            std::string::npos)
      << rn::calibration_text(steps, headset);
  EXPECT_NE(unwrapped(rn::calibration_text(steps, desk)).find("with the right hand and press space"),
            std::string::npos);
  for (int j = 0; j < 3; ++j) steps.apply(Command::touch, corner(j));
  const std::string three = unwrapped(rn::calibration_text(steps, headset));
  EXPECT_NE(three.find("back-left corner"), std::string::npos) << three;
  EXPECT_NE(three.find("press B"), std::string::npos) << three;
  steps.apply(Command::touch, corner(3));
  const std::string fitted = unwrapped(rn::calibration_text(steps, desk));
  EXPECT_NE(fitted.find("Edge 900.0 mm, height 760.0 mm"), std::string::npos) << fitted;
  EXPECT_NE(fitted.find("Residuals 0.0, 0.0, 0.0, 0.0 mm"), std::string::npos) << fitted;
  EXPECT_NE(fitted.find("Keep it: press Enter"), std::string::npos) << fitted;
  // Lines stay short enough to be read on the panel.
  for (const auto& text : {rn::calibration_text(steps, desk), rn::calibration_text(steps, headset)}) {
    std::size_t longest = 0, run = 0;
    for (char c : text) {
      run = c == '\n' ? 0 : run + 1;
      longest = std::max(longest, run);
    }
    EXPECT_LE(longest, 48u) << text;
  }
}

}  // namespace
