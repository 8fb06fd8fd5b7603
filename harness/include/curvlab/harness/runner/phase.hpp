// The phases a session shows and the reasons an attempt ends early, as types
// (DESIGN.md §6). Their names are what the data and the windows show: event
// kinds ("instructions", "break", "done"), abort reasons in trial_aborted
// events, the desktop window's status line.
#pragma once

#include <optional>
#include <string_view>

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

enum class AbortReason {
  pause,          // the participant or operator paused (focus lost, pause key)
  recenter,       // the view was recentred mid-trial
  tracking_lost,  // the head was lost for longer than [tracking] loss_ms
  quit,           // the backend ended the session (window closed, runtime exiting)
};

std::string_view to_string(Phase phase);
std::string_view to_string(AbortReason reason);
std::optional<Phase> parse_phase(std::string_view name);
std::optional<AbortReason> parse_abort_reason(std::string_view name);

}  // namespace curvlab::harness::runner
