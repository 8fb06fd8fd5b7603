// Calibration of the physical table as a step with the participant's devices
// (DESIGN.md §6; docs/devices.md, "Physical-table calibration"): the view
// shows the table as currently known, a marker on the corner to touch next,
// the points touched so far and the controller's tip; the right controller's
// tip is taken as a touch when the trigger (or the desktop's space key) is
// pressed. After four corners (or three and "fit") the square is fitted
// (geometry/calibration.hpp) and shown with each corner's residual; a fit the
// limits refuse is shown with the reason and the corners are touched again;
// an accepted fit is the result.
//
// The steps are a pure state machine (CalibrationSteps) fed with commands,
// tested without a display; run_calibration drives its own frame loop over
// an io::Station — the same devices `curvlab run` composes — before any
// session exists, so nothing is written to a data file.
#pragma once

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/harness/io/station.hpp"
#include "curvlab/harness/result.hpp"

#include <array>
#include <atomic>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

// What an input asks of the calibration.
enum class CalibrationCommand {
  touch,      // take the tip's position as the next corner
  fit_three,  // fit the three corners touched so far
  accept,     // keep the fitted table
  redo,       // forget the touches and start again
};

enum class CalibrationStage {
  touching,  // corners are being touched
  fitted,    // a fit is shown with its residuals, to be accepted or redone
  refused,   // the touches were refused (the reason is shown), to be redone
  accepted,  // the fit is kept: the calibration is over
};
std::string_view to_string(CalibrationStage stage);

// The command an input gives in a stage, if any, from what its source means
// by it (io::Intent: the headset's right trigger touches, B fits three
// corners or touches again, A accepts; the keyboard's space touches, F fits
// three corners, Enter accepts, R touches again). In the refused stage a
// touch input also starts again (without taking a touch). Releases give
// nothing.
std::optional<CalibrationCommand> calibration_command(const io::InputEvent& input, CalibrationStage stage);

// Which of those controls the devices at hand have (from their reach: a
// controller or a keyboard that can touch), so the text names only what can
// be pressed.
struct CalibrationControls {
  bool controller = false;
  bool keyboard = false;
};
CalibrationControls calibration_controls(const std::vector<io::Reach>& sources);

// The calibration's steps. Not thread-safe; plain value.
class CalibrationSteps {
 public:
  explicit CalibrationSteps(geometry::CalibrationLimits limits = {}) : limits_(limits) {}

  // Applies a command given where the touching tip is now (nullopt: the
  // controller is not tracked; a touch is then not taken and a note says
  // so). Returns whether anything visible changed; a command that means
  // nothing in the current stage changes nothing.
  bool apply(CalibrationCommand command, const std::optional<geometry::Vec3>& tip_m);

  [[nodiscard]] CalibrationStage stage() const { return stage_; }
  [[nodiscard]] const std::vector<geometry::Vec3>& touches() const { return touches_; }
  // The corner to touch next (0 front-left … 3 back-left), while touching.
  [[nodiscard]] int next_corner() const { return static_cast<int>(touches_.size()); }
  // The fit shown (fitted) or kept (accepted).
  [[nodiscard]] const std::optional<geometry::PhysicalTableFit>& fit() const { return fit_; }
  // Why the last set of touches was refused (refused stage).
  [[nodiscard]] const std::string& refusal() const { return refusal_; }
  // Every refusal so far, oldest first, and how many fits were redone.
  [[nodiscard]] const std::vector<std::string>& refusals() const { return refusals_; }
  [[nodiscard]] int redone() const { return redone_; }
  // A passing remark (a touch not taken); empty when none.
  [[nodiscard]] const std::string& note() const { return note_; }
  [[nodiscard]] const geometry::CalibrationLimits& limits() const { return limits_; }

 private:
  void fit_touches();
  void start_again();

  geometry::CalibrationLimits limits_;
  CalibrationStage stage_ = CalibrationStage::touching;
  std::vector<geometry::Vec3> touches_;
  std::optional<geometry::PhysicalTableFit> fit_;
  std::string refusal_;
  std::vector<std::string> refusals_;
  std::string note_;
  int redone_ = 0;
};

// The participant's panel for the current step: which corner to touch and
// how, the fit and its residuals, or why it was refused, with the inputs of
// the controls at hand. Lines are wrapped for the panel.
std::string calibration_text(const CalibrationSteps& steps, const CalibrationControls& controls);

struct CalibrationOptions {
  // The table as currently known: where the corner markers are drawn
  // (the protocol's nominal table, or an earlier calibration).
  geometry::PhysicalTableFit known;
  // The touching tip in the right controller's grip frame (metres; OpenXR
  // grip space: −z along the controller's barrel).
  geometry::Vec3 tip_offset_m{0.0};
  geometry::CalibrationLimits limits;
  double ipd_m = 0.063;
  // Eye images when the display does not say its own size.
  std::uint32_t width_px = 1024;
  std::uint32_t height_px = 1024;
  std::string font_path;  // empty: the renderer's default
  // Saves the view (Display::save_frame) when the calibration starts and
  // after every step, as calibration_NN_<step>; empty: none.
  std::string screenshot_dir;
  // Set by the caller's signal handler: the calibration ends unaccepted at
  // the next frame. nullptr: not watched.
  const std::atomic<int>* stop_signal = nullptr;
};

struct CalibrationResult {
  // False: the calibration ended before a fit was accepted (the window was
  // closed, the runtime asked to exit, a stop signal); the fields below then
  // hold what was done so far.
  bool accepted = false;
  geometry::PhysicalTableFit fit;
  std::vector<geometry::Vec3> touches_m;  // the accepted fit's touches
  std::vector<std::string> refusals;      // reasons of the fits refused before it
  int redone = 0;                         // sets of touches started again
  std::vector<std::string> screenshots;
};

// Runs the calibration over the station's display, pose source and response
// sources until a fit is accepted or the devices end it. A failing Vulkan or
// OpenXR call is an Error of kind `api` naming it; the font, of kind `io`.
Result<CalibrationResult> run_calibration(const io::Station& station, const CalibrationOptions& options);

}  // namespace curvlab::harness::runner
