#include "curvlab/harness/runner/phase.hpp"

#include <array>
#include <utility>

namespace curvlab::harness::runner {

namespace {

constexpr std::array<std::pair<Phase, std::string_view>, 9> phase_names{{
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

constexpr std::array<std::pair<AbortReason, std::string_view>, 4> reason_names{{
    {AbortReason::pause, "pause"},
    {AbortReason::recenter, "recenter"},
    {AbortReason::tracking_lost, "tracking_lost"},
    {AbortReason::quit, "quit"},
}};

}  // namespace

std::string_view to_string(Phase phase) {
  for (const auto& [p, name] : phase_names)
    if (p == phase) return name;
  return "unknown";
}

std::string_view to_string(AbortReason reason) {
  for (const auto& [r, name] : reason_names)
    if (r == reason) return name;
  return "unknown";
}

std::optional<Phase> parse_phase(std::string_view name) {
  for (const auto& [p, n] : phase_names)
    if (n == name) return p;
  return std::nullopt;
}

std::optional<AbortReason> parse_abort_reason(std::string_view name) {
  for (const auto& [r, n] : reason_names)
    if (n == name) return r;
  return std::nullopt;
}

}  // namespace curvlab::harness::runner
