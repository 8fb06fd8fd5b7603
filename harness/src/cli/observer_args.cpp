#include "observer_args.hpp"

#include <algorithm>

namespace curvlab::harness::cli {

namespace rn = curvlab::harness::runner;

void add_observer_options(CLI::App* cmd, ObserverArgs& o) {
  cmd->add_option("--observer", o.model,
                  "who answers in headless runs: human (default: human limits), triangulation (the ideal "
                  "geometer; 'perception' is its former name), physical (null model), random, image (the human "
                  "model reading the stick from the rendered onset pair), or none");
  cmd->add_option("--observer-bias-m", o.bias_m, "simulated observer: bias added to the perceived sagitta (m)");
  cmd->add_option("--observer-adaptation-m", o.adaptation_m,
                  "simulated observer: shift of the perceived sagitta after a play block (m; default 0)");
  cmd->add_option("--observer-slope-per-m", o.slope_per_m,
                  "simulated observer: 1 / noise SD in metres (triangulation and physical; the human model's without "
                  "disparity; default 300 /m)");
  for (const auto& setting : rn::vision_settings()) {
    std::string flag = "--observer-" + std::string(setting.name);
    std::replace(flag.begin(), flag.end(), '_', '-');
    cmd->add_option(flag, o.vision.*setting.field, "human observer: " + std::string(setting.help));
  }
  cmd->add_option("--observer-lapse", o.lapse, "simulated observer: lapse rate (default 0.02)");
  cmd->add_option("--observer-criterion-m", o.criterion_m,
                  "simulated observer: half-width of the 'straight' band (default 0.006 m)");
  cmd->add_option_function<std::uint64_t>("--observer-seed", [&o](std::uint64_t s) { o.seed = s; },
                                          "simulated observer's seed (default: from the session's seed)");
}

std::optional<rn::ObserverParams> observer_params(const ObserverArgs& a, std::uint64_t default_seed) {
  if (a.model == "none") return std::nullopt;
  const auto model = rn::parse_observer_model(a.model);
  if (!model)
    throw UsageError("--observer must be human, triangulation, physical, random, image or none, got '" + a.model +
                     "'");
  rn::ObserverParams p;
  p.model = *model;
  p.vision = a.vision;
  p.bias_m = a.bias_m;
  p.adaptation_m = a.adaptation_m;
  p.slope_per_m = a.slope_per_m;
  p.lapse = a.lapse;
  p.criterion_m = a.criterion_m;
  p.seed = a.seed.value_or(default_seed);
  if (auto ok = rn::check_observer(p); !ok) throw UsageError("--observer-*: " + ok.error().message);
  return p;
}

}  // namespace curvlab::harness::cli
