#include "operator_room.hpp"

namespace curvlab::harness::runner {

namespace {

std::optional<io::Signal> operator_signal(OperatorActionKind kind) {
  switch (kind) {
    case OperatorActionKind::pause: return io::Signal::pause;
    case OperatorActionKind::resume: return io::Signal::resume;
    case OperatorActionKind::recenter: return io::Signal::recenter;
    case OperatorActionKind::repeat: return io::Signal::repeat;
    case OperatorActionKind::skip: return io::Signal::skip;
    case OperatorActionKind::end: return io::Signal::quit;
    case OperatorActionKind::note: return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

const std::vector<data::events::OperatorActionEvent>& OperatorRoom::take(std::int64_t elapsed_ns,
                                                                          std::int64_t now_ns, io::Signal& signal) {
  actions_.clear();
  events_.clear();
  console_->take(elapsed_ns, actions_);
  for (const auto& a : actions_) {
    data::events::OperatorActionEvent action{std::string(to_string(a.kind)), a.source, now_ns, std::nullopt};
    if (a.kind == OperatorActionKind::note) action.text = a.text;
    events_.push_back(std::move(action));
    if (const auto s = operator_signal(a.kind)) signals_.push_back(*s);
  }
  if (signal == io::Signal::none && !signals_.empty()) {
    signal = signals_.front();
    signals_.pop_front();
  }
  return events_;
}

void OperatorRoom::acted() {
  for (const auto& a : actions_) console_->acted(a);
}

void OperatorRoom::show(const StatusFacts& facts, Phase phase) {
  if (console_ == nullptr) return;
  status.phase = phase;
  status.phase_left_ns = phase_left_ns;
  phase_left_ns = -1;
  status.paused = phase == Phase::paused;
  status.elapsed_ns = facts.elapsed_ns;
  // The time per trial so far, for the trials still to run.
  if (facts.trials_ended > 0)
    status.remaining_ns = facts.elapsed_ns / facts.trials_ended * (status.trials - facts.trials_ended - facts.trials_before);
  for (std::size_t d = 0; d < 3; ++d) {
    const bool tracked = facts.lab->pose[d].valid;
    if (!tracked && lost_since_[d] < 0) lost_since_[d] = facts.now_ns;
    if (tracked) lost_since_[d] = -1;
    status.tracked[d] = tracked;
    status.lost_ns[d] = tracked ? -1 : facts.now_ns - lost_since_[d];
  }
  status.cpu_ms = facts.cpu_ms;
  status.gpu_ms = facts.gpu_ms;
  status.logger_drops = facts.logger_drops;
  status.logger_lock_wait_s = facts.logger_lock_wait_s;
  console_->show(status);
}

void OperatorRoom::show_ended() {
  if (console_ == nullptr) return;
  status.ended = true;
  status.phase = Phase::done;
  status.phase_left_ns = -1;
  console_->show(status);
}

}  // namespace curvlab::harness::runner
