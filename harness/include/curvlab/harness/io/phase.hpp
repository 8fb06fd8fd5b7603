// What a session shows at a moment and what a device can ask of it, as the
// displays, pose sources and response sources see them (DESIGN.md §6). The
// names are what the data and the windows show: event kinds
// ("instructions", "break", "done") and the desktop window's status line.
#pragma once

#include <array>
#include <optional>
#include <string_view>
#include <utility>

namespace curvlab::harness::io {

enum class Phase {
  instructions,  // an instruction page
  fixation,      // the fixation mark before the stimulus
  stimulus,      // the stimulus, from its onset frame
  response,      // the response window after the stimulus time
  iti,           // the inter-trial interval: nothing on screen
  break_page,    // a break page between trials
  done,          // the closing page
  paused,        // held until the session is resumed
  tracking_lost, // held until the head is tracked again
  calibration,   // the physical table's corners are being touched (runner/calibration.hpp)
};

// Something a device (or the operator, runner/operator.hpp) wants the session
// to know in a frame: the participant paused (focus lost, headset off) or
// resumed, the view was recentred, the session is to end (window closed,
// runtime exiting, the operator's end), or the operator repeats or skips the
// current trial.
enum class Signal { none, pause, resume, quit, recenter, repeat, skip };

inline constexpr std::array<std::pair<Phase, std::string_view>, 10> kPhaseNames{{
    {Phase::instructions, "instructions"},
    {Phase::fixation, "fixation"},
    {Phase::stimulus, "stimulus"},
    {Phase::response, "response"},
    {Phase::iti, "iti"},
    {Phase::break_page, "break"},
    {Phase::done, "done"},
    {Phase::paused, "paused"},
    {Phase::tracking_lost, "tracking_lost"},
    {Phase::calibration, "calibration"},
}};

constexpr std::string_view to_string(Phase phase) {
  for (const auto& [p, name] : kPhaseNames)
    if (p == phase) return name;
  return "unknown";
}

constexpr std::optional<Phase> parse_phase(std::string_view name) {
  for (const auto& [p, n] : kPhaseNames)
    if (n == name) return p;
  return std::nullopt;
}

}  // namespace curvlab::harness::io
