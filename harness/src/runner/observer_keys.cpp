#include "observer_keys.hpp"

#include "curvlab/harness/protocol/random.hpp"

#include <algorithm>
#include <cmath>

namespace curvlab::harness::runner {

namespace {

using protocol::JudgementType;

std::string first_of(const std::vector<std::string>& keys, const std::vector<std::string>& buttons) {
  if (!keys.empty()) return keys.front();
  if (!buttons.empty()) return buttons.front();
  return {};
}

double judged_quantity(const SimulatedObserver& observer, const World& world, const protocol::Settings& s,
                       const Placement& placement, const geometry::Isometry& head) {
  if (observer.params().model == ObserverModel::physical) return physical_sagitta_m(s);
  return perceived_sagitta_m(world, s, placement, head);
}

// Coarse steps toward the value the observer settles on, then the confirm.
ObserverAnswer adjust(SimulatedObserver& observer, const World& world, const protocol::AdjustmentSpec& a,
                      const protocol::Settings& s, const geometry::Isometry& head, std::int64_t t,
                      double start) {
  auto perceived = [&](double x) {
    protocol::Settings s2 = s;
    protocol::set_numeric_setting(s2, a.parameter, x);
    return judged_quantity(observer, world, s2, place_stimulus(world, s2, head), head);
  };
  const double target = observer.adjust(perceived, a.min, a.max);
  ObserverAnswer out;
  out.perceived_m = perceived(start);
  const std::string up = first_of(a.keys_increase, a.buttons_increase);
  const std::string down = first_of(a.keys_decrease, a.buttons_decrease);
  double v = start;
  for (int presses = 0; std::abs(target - v) > a.step / 2.0 && presses < 400; ++presses) {
    const bool inc = target > v;
    out.keys.push_back({t, inc ? up : down});
    v = std::clamp(v + (inc ? a.step : -a.step), a.min, a.max);
    t += 80'000'000;
  }
  out.keys.push_back({t + 200'000'000, first_of(a.keys_confirm, a.buttons_confirm)});
  return out;
}

}  // namespace

std::uint64_t attempt_seed(std::uint64_t observer_seed, std::uint64_t session_seed, std::size_t trial_index,
                           std::int64_t attempt) {
  std::uint64_t x = protocol::mix_seed(observer_seed ^ protocol::mix_seed(session_seed));
  x = protocol::mix_seed(x ^ protocol::mix_seed(static_cast<std::uint64_t>(trial_index)));
  return protocol::mix_seed(x ^ static_cast<std::uint64_t>(attempt));
}

ObserverAnswer plan_answer(SimulatedObserver& observer, const World& world, const protocol::Judgement& j,
                           const protocol::Settings& s, const Placement& placement,
                           const geometry::Isometry& head, std::int64_t onset_ns,
                           const std::optional<protocol::Adjustment>& adjustment, std::optional<double> seen_m) {
  const std::int64_t rt = observer.response_time_ns();
  if (j.type == JudgementType::adjustment)
    return adjust(observer, world, *j.adjustment, s, head, onset_ns + rt, adjustment->value());
  ObserverAnswer out;
  out.perceived_m = seen_m ? *seen_m : judged_quantity(observer, world, s, placement, head);
  const auto& option = j.options.at(observer.choose(out.perceived_m, j.options.size()));
  const std::string key = first_of(option.keys, option.buttons);
  out.keys.push_back({onset_ns + rt, key.empty() ? option.value : key});
  return out;
}

}  // namespace curvlab::harness::runner
