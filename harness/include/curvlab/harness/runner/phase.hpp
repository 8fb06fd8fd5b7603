// The phases a session shows and the reasons an attempt ends early, as types
// (DESIGN.md §6). Their names are what the data and the windows show: event
// kinds ("instructions", "break", "done"), abort reasons in trial_aborted
// events, the desktop window's status line.
#pragma once

#include "curvlab/harness/io/phase.hpp"

#include <array>
#include <optional>
#include <string_view>
#include <utility>

namespace curvlab::harness::runner {

using io::Phase;
using io::Signal;
using io::parse_phase;
using io::to_string;

enum class AbortReason {
  pause,          // the participant or operator paused (focus lost, pause key)
  recenter,       // the view was recentred mid-trial
  tracking_lost,  // the head was lost for longer than [tracking] loss_ms
  quit,           // the backend ended the session (window closed, runtime exiting)
  repeat,         // the operator repeats the trial (always run again)
  skip,           // the operator skips the trial (stored skipped, never run again)
};

namespace phase_names {
inline constexpr std::array<std::pair<AbortReason, std::string_view>, 6> reasons{{
    {AbortReason::pause, "pause"},
    {AbortReason::recenter, "recenter"},
    {AbortReason::tracking_lost, "tracking_lost"},
    {AbortReason::quit, "quit"},
    {AbortReason::repeat, "operator_repeat"},
    {AbortReason::skip, "operator_skip"},
}};
}  // namespace phase_names

constexpr std::string_view to_string(AbortReason reason) {
  for (const auto& [r, name] : phase_names::reasons)
    if (r == reason) return name;
  return "unknown";
}

constexpr std::optional<AbortReason> parse_abort_reason(std::string_view name) {
  for (const auto& [r, n] : phase_names::reasons)
    if (n == name) return r;
  return std::nullopt;
}

}  // namespace curvlab::harness::runner
