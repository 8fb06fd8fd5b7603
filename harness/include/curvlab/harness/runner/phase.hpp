// The phases a session shows and the reasons an attempt ends early, as types
// (DESIGN.md §6). Their names are what the data and the windows show: event
// kinds ("instructions", "break", "done"), abort reasons in trial_aborted
// events, the desktop window's status line.
#pragma once

#include <array>
#include <optional>
#include <string_view>
#include <utility>

namespace curvlab::harness::runner {

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
};

// Something the backend (or the operator, operator.hpp) wants the runner to
// know in a frame: the participant paused (focus lost, headset off) or
// resumed, the view was recentred, the session is to end (window closed,
// runtime exiting, the operator's end), or the operator repeats or skips the
// current trial.
enum class BackendSignal { none, pause, resume, quit, recenter, repeat, skip };

enum class AbortReason {
  pause,          // the participant or operator paused (focus lost, pause key)
  recenter,       // the view was recentred mid-trial
  tracking_lost,  // the head was lost for longer than [tracking] loss_ms
  quit,           // the backend ended the session (window closed, runtime exiting)
  repeat,         // the operator repeats the trial (always run again)
  skip,           // the operator skips the trial (stored skipped, never run again)
};

namespace phase_names {
inline constexpr std::array<std::pair<Phase, std::string_view>, 9> phases{{
    {Phase::instructions, "instructions"},
    {Phase::fixation, "fixation"},
    {Phase::stimulus, "stimulus"},
    {Phase::response, "response"},
    {Phase::iti, "iti"},
    {Phase::break_page, "break"},
    {Phase::done, "done"},
    {Phase::paused, "paused"},
    {Phase::tracking_lost, "tracking_lost"},
}};
inline constexpr std::array<std::pair<AbortReason, std::string_view>, 6> reasons{{
    {AbortReason::pause, "pause"},
    {AbortReason::recenter, "recenter"},
    {AbortReason::tracking_lost, "tracking_lost"},
    {AbortReason::quit, "quit"},
    {AbortReason::repeat, "operator_repeat"},
    {AbortReason::skip, "operator_skip"},
}};
}  // namespace phase_names

constexpr std::string_view to_string(Phase phase) {
  for (const auto& [p, name] : phase_names::phases)
    if (p == phase) return name;
  return "unknown";
}

constexpr std::string_view to_string(AbortReason reason) {
  for (const auto& [r, name] : phase_names::reasons)
    if (r == reason) return name;
  return "unknown";
}

constexpr std::optional<Phase> parse_phase(std::string_view name) {
  for (const auto& [p, n] : phase_names::phases)
    if (n == name) return p;
  return std::nullopt;
}

constexpr std::optional<AbortReason> parse_abort_reason(std::string_view name) {
  for (const auto& [r, n] : phase_names::reasons)
    if (n == name) return r;
  return std::nullopt;
}

}  // namespace curvlab::harness::runner
