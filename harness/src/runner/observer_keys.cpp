#include "observer_keys.hpp"

#include "curvlab/harness/protocol/random.hpp"

namespace curvlab::harness::runner {

namespace {

io::InputEvent observer_press(std::int64_t t_ns, io::Control control, io::Intents intents) {
  io::InputEvent in;
  in.t_ns = t_ns;
  in.source = {io::SourceKind::observer, ""};
  in.control = std::move(control);
  in.intents = intents;
  return in;
}

}  // namespace

// The press is named after what it does: nothing stores a page's press.
void ObserverKeys::press_continue(std::int64_t t_ns) {
  const io::Intent go = io::Intent::continue_page;
  due_.push_back(observer_press(t_ns, {io::ControlKind::key, std::string(io::to_string(go))}, {go}));
}

void ObserverKeys::replace(const std::vector<ScheduledKey>& keys) {
  due_.clear();
  for (const auto& k : keys)
    due_.push_back(observer_press(k.t_ns, {k.button ? io::ControlKind::button : io::ControlKind::key, k.name}, {}));
}

io::Signal ObserverKeys::poll(std::vector<io::InputEvent>& out) {
  const std::int64_t now = clock_.now_ns();
  while (!due_.empty() && due_.front().t_ns <= now) {
    out.push_back(std::move(due_.front()));
    due_.pop_front();
  }
  return io::Signal::none;
}

namespace {

// The simulated observer in the stimulus of one trial, as the judgement
// types ask for it. A choice answers the percept judged last (the onset's,
// or a value a type asked about).
class ObserverRespondent final : public protocol::Respondent {
 public:
  ObserverRespondent(SimulatedObserver& observer, const World& world, const protocol::Settings& s,
                     const Placement& placement, const geometry::Isometry& head, std::optional<Percept> seen)
      : observer_(observer), world_(world), s_(s), placement_(placement), head_(head), seen_(std::move(seen)) {}

  // The onset's percept.
  const Percept& onset() {
    if (!seen_) seen_ = perceive(world_, s_, placement_, head_, observer_.params());
    return *seen_;
  }

  double judged() override {
    last_noise_m_ = onset().noise_sd_m;
    return onset().sagitta_m;
  }

  double judged_at(const std::string& parameter, double value) override {
    protocol::Settings s2 = s_;
    protocol::set_numeric_setting(s2, parameter, value);
    const Percept p = perceive(world_, s2, place_stimulus(world_, s2, head_), head_, observer_.params());
    last_noise_m_ = p.noise_sd_m;
    return p.sagitta_m;
  }

  std::size_t choose(double judged, std::size_t n) override { return observer_.choose(judged, n, last_noise_m_); }

  double settle(const std::string& parameter, double min, double max) override {
    const double noise = onset().noise_sd_m;
    return observer_.adjust([&](double x) { return judged_at(parameter, x); }, min, max, noise);
  }

 private:
  SimulatedObserver& observer_;
  const World& world_;
  const protocol::Settings& s_;
  const Placement& placement_;
  const geometry::Isometry& head_;
  std::optional<Percept> seen_;
  double last_noise_m_ = 0.0;
};

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
                           const std::optional<protocol::Adjustment>& adjustment, std::optional<Percept> seen) {
  const std::int64_t rt = observer.response_time_ns();
  ObserverRespondent who(observer, world, s, placement, head, std::move(seen));
  ObserverAnswer out{j.type->plan_answer(j, who, onset_ns + rt, adjustment), {}};
  out.percept = who.onset();
  return out;
}

}  // namespace curvlab::harness::runner
