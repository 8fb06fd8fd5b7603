// The display refresh rate curvlab asks a headset for (docs/xr.md, "The
// runtime's other events"): a lab fixes the rate for its timing, so curvlab
// asks for the protocol's [backend] refresh_hz where the runtime offers it
// (XR_FB_display_refresh_rate), keeps and says the display's own where it
// does not, and asks again when the runtime changes the rate itself. A pure
// value, like session_state.hpp: rates in, decisions out; the swapchain
// display (swapchain_display.hpp) makes the OpenXR calls. Not thread-safe.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace curvlab::harness::xr {

class RefreshRatePolicy {
 public:
  // `wanted_hz`: the protocol's rate; nullopt: the runtime's, never asked for.
  explicit RefreshRatePolicy(std::optional<double> wanted_hz) : wanted_hz_(wanted_hz) {}

  // The rate the display runs at as far as curvlab knows (90 Hz, the common
  // rate, until the display says).
  [[nodiscard]] double current_hz() const { return current_hz_; }
  // The display said its rate (xrGetDisplayRefreshRateFB).
  void display_runs_at(double hz) { current_hz_ = hz; }

  // Whether the protocol's rate must be asked for: there is one and the
  // display runs at another (more than 0.5 Hz away).
  [[nodiscard]] bool should_request() const;
  // Among the rates the display offers, the one to ask for; nullopt: it
  // offers none within 0.5 Hz of the protocol's.
  [[nodiscard]] std::optional<float> choose(const std::vector<float>& offered) const;
  // What the experimenter is told when the protocol's rate is not offered.
  [[nodiscard]] std::string not_offered_message(const std::vector<float>& offered) const;
  // The request for `rate` went through and the display now runs at `now_hz`;
  // the change event it brings is expected (on_change).
  void requested(float rate, double now_hz);

  // The runtime announced a change to `to_hz`. true: the answer to curvlab's
  // own request, already recorded (nothing to do). false: the runtime's own
  // change; the rate is now `to_hz`, to be recorded and said, and the
  // protocol's rate asked for again (should_request).
  bool on_change(float to_hz);

 private:
  std::optional<double> wanted_hz_;
  double current_hz_ = 90.0;
  float requested_hz_ = 0.0f;  // the rate asked for; its change event is expected (0: none)
};

}  // namespace curvlab::harness::xr
