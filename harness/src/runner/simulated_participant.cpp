#include "simulated_participant.hpp"

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

}  // namespace curvlab::harness::runner
