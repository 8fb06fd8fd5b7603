// The simulated observer's options, shared by `curvlab run`, `resume` and
// `predict`: the flags, and the observer they describe.
#pragma once

#include "common.hpp"

#include "curvlab/geometry/human_vision.hpp"
#include "curvlab/harness/runner/observer.hpp"

#include <CLI/CLI.hpp>

#include <cstdint>
#include <optional>
#include <string>

namespace curvlab::harness::cli {

struct ObserverArgs {
  std::string model = "human";
  geometry::HumanVision vision;
  double bias_m = 0.0;
  double adaptation_m = 0.0;
  double slope_per_m = 300.0;
  double lapse = 0.02;
  double criterion_m = 0.006;
  std::optional<std::uint64_t> seed;
};

void add_observer_options(CLI::App* cmd, ObserverArgs& o);

// The observer the options describe (nullopt: --observer none), its seed
// `default_seed` unless --observer-seed is given; a bad value is a
// UsageError.
std::optional<harness::runner::ObserverParams> observer_params(const ObserverArgs& a, std::uint64_t default_seed);

}  // namespace curvlab::harness::cli
