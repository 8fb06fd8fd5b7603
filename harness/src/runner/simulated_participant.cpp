#include "simulated_participant.hpp"

#include "curvlab/harness/protocol/random.hpp"

namespace curvlab::harness::runner {

SimulatedParticipant::SimulatedParticipant(const ObserverParams& params, std::uint64_t session_seed,
                                           const io::Clock& clock)
    : params_(params), session_seed_(session_seed), keys_(clock) {}

std::unique_ptr<SimulatedParticipant> SimulatedParticipant::seat(SessionSetup& setup) {
  if (!setup.options.observer) return nullptr;
  auto participant = std::make_unique<SimulatedParticipant>(*setup.options.observer, setup.design.seed, *setup.clock);
  // Trials after a play block carry the hypothesised adaptation.
  bool played = false;
  for (const auto& block : setup.design.blocks) {
    for (std::size_t i = 0; i < block.trial_count; ++i) participant->after_play_.push_back(played);
    played = played || block.kind == "play";
  }
  // Last among the sources: its presses come after the devices' in a frame.
  setup.station.responses.push_back(participant.get());
  setup.watchers.push_back(participant.get());
  return participant;
}

// Pages are continued 300 ms after they may be.
void SimulatedParticipant::page_shown(std::int64_t shown_ns, std::int64_t min_ns) {
  keys_.press_continue(shown_ns + min_ns + 300'000'000);
}

// Each attempt draws from its own stream (attempt_seed), so a resumed
// session answers as the uninterrupted one would.
void SimulatedParticipant::attempt_begins(std::size_t trial_index, std::int64_t draw) {
  ObserverParams op = params_;
  op.seed = attempt_seed(params_.seed, session_seed_, trial_index, draw);
  if (trial_index < after_play_.size() && after_play_[trial_index]) op.bias_m += params_.adaptation_m;
  observer_.emplace(op);
  keys_.clear();
}

std::optional<OnsetNote> SimulatedParticipant::onset(const OnsetFacts& f) {
  std::optional<Percept> seen;
  if (params_.model == ObserverModel::image) {
    // The image observer reads the onset pair as drawn.
    if (!onset_reader_) {
      auto reader = OnsetReader::create();
      if (!reader) throw Stop{reader.error()};
      onset_reader_ = std::move(reader).value();
    }
    auto read = onset_reader_->read(f.world, f.settings, f.placement, f.view, observer_->params());
    if (!read) throw Stop{read.error()};
    seen = std::move(read).value();
  }
  auto answer = plan_answer(*observer_, f.world, f.judgement, f.settings, f.placement, f.head, f.onset_ns,
                            f.adjustment, std::move(seen));
  keys_.replace(answer.plan.keys);
  return OnsetNote{answer.plan.perceived_m, answer.percept.human};
}

namespace {

protocol::Engine item_stream(std::uint64_t session_seed, const ItemFacts& f) {
  return protocol::Engine(protocol::mix_seed(session_seed ^ protocol::mix_seed(0x5e550000ULL + f.trial_index) ^
                                             protocol::mix_seed(0x17e30000ULL + f.item)));
}

}  // namespace

std::size_t simulated_item_answer(std::uint64_t session_seed, const ItemFacts& f, bool after_play) {
  protocol::Engine rng = item_stream(session_seed, f);
  const std::size_t n = f.instrument.scale.size();
  if (f.instrument.name == protocol::kSsqName) {
    const double before[] = {0.55, 0.30, 0.12, 0.03}, after[] = {0.35, 0.38, 0.20, 0.07};
    const double* p = after_play ? after : before;
    double u = protocol::uniform01(rng);
    for (std::size_t k = 0; k + 1 < n; ++k) {
      if (u < p[k]) return k;
      u -= p[k];
    }
    return n - 1;
  }
  // A binomial draw over the scale's points: the middle most often.
  std::size_t k = 0;
  for (std::size_t i = 0; i + 1 < n; ++i) k += protocol::uniform01(rng) < 0.5 ? 1 : 0;
  return k;
}

// The item's digit key, after 0.8 to 2 s of reading.
void SimulatedParticipant::item_shown(const ItemFacts& f) {
  const bool after_play = f.trial_index < after_play_.size() && after_play_[f.trial_index];
  const std::size_t point = simulated_item_answer(session_seed_, f, after_play);
  protocol::Engine rng = item_stream(session_seed_ ^ 0x7ea0ULL, f);
  const auto read_ns = static_cast<std::int64_t>((0.8 + 1.2 * protocol::uniform01(rng)) * 1e9);
  keys_.replace({ScheduledKey{f.shown_ns + read_ns, f.instrument.scale[point].key, false}});
}

}  // namespace curvlab::harness::runner
