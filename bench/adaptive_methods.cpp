// The psi method against a 1-up/1-down staircase on the same stimulus grid,
// both answered by the simulated observer (runner/observer.hpp) with a known
// PSE and slope, many seeds each. Prints, per observer, the trials each
// method needs before its PSE estimate's RMS error over the seeds falls to
// 2 mm and to 1 mm (its standard error, bias included), and the bias and RMS
// error at 20, 40 and 80 trials.
//
//   bench_adaptive_methods [SEEDS]     (default 200)
//
// The psi is the `psi` judgement type (judgements/psi.cpp) driven through the
// judgement interface; its estimate is the posterior mean of the PSE. The
// staircase is the project's Staircase (protocol/staircase.hpp), 1-up/1-down
// on the same grid (steps of 4, 2 and then 1 grid step, clamped to the
// grid's range), starting at a grid value drawn in [−30, 30] mm per seed; its
// estimate is the mean of the reversal values after the first two
// (Staircase::threshold(), Levitt 1971), before that the mean of the
// reversals so far, before the first reversal the value it would show next.
#include "curvlab/harness/protocol/design.hpp"
#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/loader.hpp"
#include "curvlab/harness/protocol/random.hpp"
#include "curvlab/harness/protocol/staircase.hpp"
#include "curvlab/harness/runner/observer.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <string>
#include <vector>

namespace pr = curvlab::harness::protocol;
namespace rn = curvlab::harness::runner;

namespace {

constexpr int kMaxTrials = 80;
constexpr double kGridMin = -0.06, kGridMax = 0.06;
constexpr int kGridCount = 49;  // 2.5 mm apart
constexpr double kGridStep = (kGridMax - kGridMin) / (kGridCount - 1);
constexpr double kLapse = 0.02;

const std::string kProtocol =
    "[protocol]\nname = \"bench\"\nversion = \"1\"\n[randomization]\nseed = 1\n"
    "[judgement]\ntype = \"psi\"\nparameter = \"stimulus.stick_sagitta_m\"\npositive = \"convex\"\n"
    "options = [{ value = \"convex\", keys = [\"1\"] }, { value = \"concave\", keys = [\"2\"] }]\n"
    "values = { min = -0.06, max = 0.06, count = 49 }\n"
    "pse = { min = -0.06, max = 0.06, count = 97 }\n"
    "slope = { min = 20.0, max = 2000.0, count = 15 }\n"
    "lapse = 0.02\ntrials = 80\n";

struct Observer {
  double pse_m, slope_per_m;
};

// Each seed's PSE estimate after 1 … kMaxTrials trials.
using Track = std::vector<double>;

rn::SimulatedObserver make_observer(const Observer& o, std::uint64_t seed) {
  rn::ObserverParams p;
  p.bias_m = -o.pse_m;  // P(convex | x) = Φ(slope (x + bias))
  p.slope_per_m = o.slope_per_m;
  p.lapse = kLapse;
  p.seed = seed;
  return rn::SimulatedObserver(p);
}

Track run_psi(const pr::Judgement& j, const pr::PlannedTrial& slot, const Observer& o, std::uint64_t seed) {
  auto observer = make_observer(o, seed);
  auto state = j.type->adaptive_state(j);
  Track out;
  for (int n = 0; n < kMaxTrials; ++n) {
    const pr::AdaptiveStep step = state->record(slot, observer.choose(state->value(slot), 2, observer.metric_noise_sd_m()) == 0);
    out.push_back(step.posterior->pse_mean);
  }
  return out;
}

double staircase_estimate(const pr::Staircase& s) {
  if (const auto t = s.threshold()) return *t;
  const auto& r = s.reversal_values();
  if (!r.empty()) return std::accumulate(r.begin(), r.end(), 0.0) / static_cast<double>(r.size());
  return s.value();
}

Track run_staircase(const Observer& o, std::uint64_t seed) {
  auto observer = make_observer(o, seed);
  pr::Engine rng(pr::mix_seed(seed ^ 0x5354414952ULL));
  const int start_steps = static_cast<int>(std::floor(pr::uniform01(rng) * 25.0)) - 12;  // −30 … +30 mm
  pr::StaircaseSpec spec;
  spec.name = "s";
  spec.start = start_steps * kGridStep;
  spec.up = 1;
  spec.down = 1;
  spec.step_sizes = {4 * kGridStep, 2 * kGridStep, kGridStep};
  spec.stop_reversals = 100;
  spec.max_trials = kMaxTrials;
  spec.discard_reversals = 2;
  spec.min = kGridMin;
  spec.max = kGridMax;
  pr::Staircase s(spec);
  Track out;
  for (int n = 0; n < kMaxTrials; ++n) {
    s.respond(observer.choose(s.value(), 2, observer.metric_noise_sd_m()) == 0);
    out.push_back(staircase_estimate(s));
  }
  return out;
}

struct Error {
  double bias = 0.0, rms = 0.0;
};

// Bias and RMS error over the seeds after n trials.
Error error_after(const std::vector<Track>& tracks, int n, double truth) {
  Error e;
  for (const auto& t : tracks) {
    const double d = t[static_cast<std::size_t>(n - 1)] - truth;
    e.bias += d;
    e.rms += d * d;
  }
  e.bias /= static_cast<double>(tracks.size());
  e.rms = std::sqrt(e.rms / static_cast<double>(tracks.size()));
  return e;
}

// The first trial count from which the RMS error stays at or below `target`.
std::string trials_to(const std::vector<Track>& tracks, double truth, double target) {
  for (int n = 1; n <= kMaxTrials; ++n) {
    bool stays = true;
    for (int m = n; m <= kMaxTrials && stays; ++m) stays = error_after(tracks, m, truth).rms <= target;
    if (stays) return std::to_string(n);
  }
  // Appends, not operator+ on a literal: GCC 12 warns falsely (-Wrestrict).
  return std::string(">").append(std::to_string(kMaxTrials));
}

}  // namespace

int main(int argc, char** argv) {
  const int seeds = argc > 1 ? std::atoi(argv[1]) : 200;
  if (seeds < 2) {
    std::fprintf(stderr, "usage: bench_adaptive_methods [SEEDS ≥ 2]\n");
    return 2;
  }
  const auto loaded = pr::load_protocol_text(kProtocol, "bench.toml");
  if (!loaded) {
    std::fprintf(stderr, "bench protocol does not load\n");
    return 1;
  }
  const pr::Judgement& j = loaded->blocks.at(0).judgement;
  const pr::Design design = pr::expand_design(*loaded, 1);
  const pr::PlannedTrial& slot = design.trials.at(0);

  const std::vector<Observer> observers{{-0.02, 150.0}, {0.0, 150.0}, {0.013, 150.0},
                                        {-0.02, 400.0}, {0.0, 400.0}, {0.013, 400.0}};
  std::printf("psi vs 1-up/1-down staircase: stimulus grid [%g, %g] m, %d values (%.1f mm apart); "
              "observer lapse %.2f; %d seeds per observer\n",
              kGridMin, kGridMax, kGridCount, kGridStep * 1000.0, kLapse, seeds);
  std::printf("psi: PSE grid 97 values, slope grid 15 log-spaced in [20, 2000] /m, lapse fixed at %.2f; estimate = "
              "posterior mean\n", kLapse);
  std::printf("staircase: steps 10, 5, 2.5 mm after 0, 1, 2+ reversals, start drawn in [-30, 30] mm; estimate = "
              "mean of reversals after the first 2 (reversal mean)\n\n");

  std::printf("trials until the RMS error of the PSE estimate over the seeds stays <= target\n");
  std::printf("%-10s %-10s | %-8s %-8s | %-8s %-8s\n", "PSE (mm)", "slope /m", "psi 2mm", "stc 2mm", "psi 1mm",
              "stc 1mm");
  std::vector<std::vector<Track>> psi(observers.size()), stair(observers.size());
  double psi_s = 0.0;
  for (std::size_t i = 0; i < observers.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int s = 1; s <= seeds; ++s) psi[i].push_back(run_psi(j, slot, observers[i], static_cast<std::uint64_t>(s)));
    psi_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (int s = 1; s <= seeds; ++s) stair[i].push_back(run_staircase(observers[i], static_cast<std::uint64_t>(s)));
    const Observer& o = observers[i];
    std::printf("%-10.1f %-10.0f | %-8s %-8s | %-8s %-8s\n", o.pse_m * 1000.0, o.slope_per_m,
                trials_to(psi[i], o.pse_m, 0.002).c_str(), trials_to(stair[i], o.pse_m, 0.002).c_str(),
                trials_to(psi[i], o.pse_m, 0.001).c_str(), trials_to(stair[i], o.pse_m, 0.001).c_str());
  }

  std::printf("\nbias and RMS error of the PSE estimate (mm) after n trials\n");
  std::printf("%-10s %-10s %-4s | %-8s %-8s | %-8s %-8s\n", "PSE (mm)", "slope /m", "n", "psi bias", "psi rms",
              "stc bias", "stc rms");
  for (std::size_t i = 0; i < observers.size(); ++i)
    for (const int n : {20, 40, 80}) {
      const Error p = error_after(psi[i], n, observers[i].pse_m), s = error_after(stair[i], n, observers[i].pse_m);
      std::printf("%-10.1f %-10.0f %-4d | %+-8.2f %-8.2f | %+-8.2f %-8.2f\n", observers[i].pse_m * 1000.0,
                  observers[i].slope_per_m, n, p.bias * 1000.0, p.rms * 1000.0, s.bias * 1000.0, s.rms * 1000.0);
    }
  std::printf("\npsi: %.2f ms per trial (posterior update and the next value)\n",
              psi_s * 1000.0 / (static_cast<double>(observers.size()) * seeds * kMaxTrials));
  return 0;
}
