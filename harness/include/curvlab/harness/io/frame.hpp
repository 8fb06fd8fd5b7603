// The plain values a session exchanges with its devices each frame (DESIGN.md
// §6): when the frame is shown, the inputs that arrived, what the runner
// shows besides the scene, and the one exception a device throws while the
// session runs. Free of Vulkan, OpenXR and GLFW.
#pragma once

#include "curvlab/harness/io/input.hpp"
#include "curvlab/harness/io/phase.hpp"

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace curvlab::harness::io {

// A Vulkan, OpenXR or window call that failed while a session runs: a lost
// device, a lost session, a runtime that failed. It is the only exception a
// display, pose source or response source throws (STYLE.md: exceptions for
// what the frame loop cannot go on from), caught by the session runner. The
// message names the call and its result as the C APIs spell them —
// "vkQueueSubmit: VK_ERROR_DEVICE_LOST", "xrWaitFrame: XR_ERROR_SESSION_LOST"
// — followed by any detail. The runner ends the session `interrupted`
// (completed trials are already committed), and it can be resumed. A device
// that threw is not used again, only destroyed; destructors never throw.
struct DeviceFailure : std::runtime_error {
  DeviceFailure(std::string call_name, std::string result_name, const std::string& detail = {})
      : std::runtime_error(call_name + ": " + result_name + (detail.empty() ? "" : " (" + detail + ")")),
        call(std::move(call_name)),
        result(std::move(result_name)) {}

  std::string call;    // "vkQueueSubmit", "xrWaitFrame"
  std::string result;  // "VK_ERROR_DEVICE_LOST", "XR_ERROR_SESSION_LOST"
};

struct FrameTiming {
  std::int64_t index = 0;              // frames since the display started
  std::int64_t now_ns = 0;             // session clock when the frame began
  std::int64_t predicted_display_ns = 0;  // when this frame's image will be shown
  std::int64_t period_ns = 11'111'111;
  // The runtime's verdict on this frame (OpenXR): its display time skipped
  // `skipped_periods` refreshes after the previous frame's (the loop missed
  // them), or it is not shown at all (shouldRender false). Late frames are
  // counted per trial (docs/xr.md, "Frame timing").
  std::int32_t skipped_periods = 0;
  bool late = false;
};

// One answer of the judgement on screen and the inputs that give it.
struct AnswerInputs {
  std::string answer;  // an option's value, or "decrease", "increase", "confirm"
  std::vector<std::string> keys;
  std::vector<std::string> buttons;
};

// What the runner shows besides the scene (for desktop windows and logs).
// Instruction pages and breaks advance on an input whose source means
// "continue" by it (Intent::continue_page, input.hpp); responses come from
// the keys and buttons of the judgement's options.
struct Overlay {
  Overlay() = default;
  Overlay(Phase p, std::string line, bool waiting) : phase(p), text(std::move(line)), waiting_for_input(waiting) {}

  Phase phase = Phase::iti;
  std::string text;   // trial information line (block, trial, condition)
  bool waiting_for_input = false;  // instructions, response window, break
  // During a trial: the judgement's question, its answers with their inputs
  // (the pilot window's key legend, shown while waiting_for_input), and the
  // value an adaptive method or an adjustment shows
  // ("stimulus.stick_sagitta_m = 0.0125").
  std::string prompt;
  std::vector<AnswerInputs> answers;
  std::string value;
};

}  // namespace curvlab::harness::io
