// The experimenter's operator window (DESIGN.md §6; docs/xr.md, "The operator window"): a GLFW
// window on the desktop showing the participant's view — copies of the
// images submitted to the headset (Display::mirror()), never rendered a
// second time — and a status panel, and taking the operator's actions by key.
//
// Threads: GLFW wants windows made, polled and destroyed on the main thread,
// which is the session's frame thread, so that thread only creates the
// window, polls its events every few frames (take()) and copies the status
// when the drawing thread asked for one (show(): a flag test per frame).
// A drawing thread of its own owns the OpenGL context: at ~15 Hz it takes
// the latest mirror copy, lays out the eye image and the status text (the
// renderer's text rasteriser) on the CPU, draws it with glDrawPixels and
// presents without vsync. Screenshots (--operator-screenshot) are read back
// from the window's framebuffer on that thread.
//
// Owns the window, the drawing thread and (when asked) the GLFW library;
// not copyable. Must be destroyed before the backend whose mirror it reads.
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/io/display.hpp"
#include "curvlab/harness/runner/operator.hpp"

#include <memory>
#include <string>
#include <vector>

namespace curvlab::harness::operator_console {

enum class EyeView { both, left, right };

struct OperatorWindowOptions {
  std::vector<runner::OperatorAction> script;  // --operator-script, parsed
  io::FrameMirror* mirror = nullptr;       // nullptr: status panel only
  EyeView eyes = EyeView::both;
  std::string screenshot_dir;  // PNGs at each action and at the end ("" none)
  std::string db_dir;          // free disk space is read here
  std::string font_path;       // "" the renderer's default
  bool terminate_glfw = true;  // false when another GLFW window (desktop) shares the library
};

// An Error of kind `device` when no window can be opened (no display).
Result<std::unique_ptr<runner::OperatorConsole>> open_operator_window(OperatorWindowOptions options);

}  // namespace curvlab::harness::operator_console
