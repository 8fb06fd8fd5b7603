// The questionnaire block kind (docs/questionnaires.md): an instrument's
// items, one page each, answered on its scale in the headset. The block is
// one planned trial; each answer is committed in its own transaction before
// the next item comes up, so a killed block resumes at its first unanswered
// item. When the last item is answered the instrument's subscales are scored
// (protocol/questionnaire.hpp) and stored with the block.
//
// Answers come from the devices at hand, through bindings as a judgement's
// answers do: a scale point's digit key (the desktop, key scripts, the
// simulated participant) or its button hid_<n> (a button box); on a
// controller, X and A move the marked point left and right and either
// trigger chooses it. Backspace, or B, goes back one item, whose answer is
// then replaced.
#include "../block_kind.hpp"

#include "curvlab/harness/protocol/questionnaire.hpp"

#include <algorithm>

namespace curvlab::harness::runner {

namespace {

namespace events = curvlab::harness::data::events;
using protocol::Instrument;

enum class ItemAction { previous_point, next_point, choose_marked, back };

struct ItemControl {
  ItemAction action;
  std::vector<std::string> keys;
  std::vector<std::string> buttons;
};

// The controls every item understands besides its scale points' own.
const std::vector<ItemControl>& item_controls() {
  static const std::vector<ItemControl> controls{
      {ItemAction::previous_point, {"left"}, {"x", "left_thumbstick_left", "right_thumbstick_left"}},
      {ItemAction::next_point, {"right"}, {"a", "left_thumbstick_right", "right_thumbstick_right"}},
      {ItemAction::choose_marked, {"enter", "space"}, {"left_trigger", "right_trigger"}},
      {ItemAction::back, {"backspace"}, {"b"}},
  };
  return controls;
}

// The scale as answer bindings, in the scale's order.
std::vector<io::AnswerInputs> scale_inputs(const Instrument& ins) {
  std::vector<io::AnswerInputs> out;
  for (const auto& p : ins.scale) out.push_back({std::to_string(p.value), {p.key}, {p.button}});
  return out;
}

// The line under each item: the marked point, and how to answer and go back
// with the devices at hand (the participant is told only of controls they
// have).
std::string controls_line(const Instrument& ins, std::size_t marked, bool can_go_back,
                          const std::vector<io::Reach>& reach) {
  bool keys = false, controllers = false, box = false;
  for (const auto& r : reach) {
    keys = keys || r.every_key || r.simulated;
    controllers = controllers || r.kind == io::SourceKind::xr_controller;
    box = box || (r.kind == io::SourceKind::hid && r.gives_button("hid_1"));
  }
  std::vector<std::string> ways, backs;
  if (keys) {
    ways.emplace_back("press its number, or move the mark with the arrow keys and press Enter");
    backs.emplace_back("Backspace");
  }
  if (controllers) {
    ways.emplace_back("move the mark with X and A and press a trigger");
    backs.emplace_back("B");
  }
  if (box) ways.emplace_back("press its button on the box (the first button for the first point)");
  std::string line = "Marked: ";
  (line += ins.scale[marked].key) += ' ';
  line += ins.scale[marked].label;
  for (std::size_t k = 0; k < ways.size(); ++k) (line += k == 0 ? ". To answer, " : "; or ") += ways[k];
  if (can_go_back && !backs.empty()) {
    line += ". ";
    for (std::size_t k = 0; k < backs.size(); ++k) (line += k == 0 ? "" : " or ") += backs[k];
    line += " goes back one item";
  }
  return line;
}

// What one frame's inputs do to an item: the point chosen, or a step back.
struct ItemStep {
  std::optional<std::pair<std::size_t, io::InputEvent>> chosen;
  bool back = false;
  bool moved = false;
};

ItemStep take_inputs(const std::vector<io::InputEvent>& inputs, const std::vector<io::AnswerInputs>& scale,
                     std::size_t& marked, std::int64_t shown_ns) {
  ItemStep step;
  for (const auto& in : inputs) {
    // Presses stamped before the item came up were for what was shown before.
    if (!in.pressed || in.t_ns < shown_ns || step.chosen || step.back) continue;
    if (const auto k = io::answer_index(scale, in.control)) {
      step.chosen = std::pair{*k, in};
      continue;
    }
    const auto c = io::answer_index(item_controls(), in.control);
    if (!c) continue;
    switch (item_controls()[*c].action) {
      case ItemAction::previous_point:
        if (marked > 0) --marked;
        step.moved = true;
        break;
      case ItemAction::next_point:
        if (marked + 1 < scale.size()) ++marked;
        step.moved = true;
        break;
      case ItemAction::choose_marked: step.chosen = std::pair{marked, in}; break;
      case ItemAction::back: step.back = true; break;
    }
  }
  return step;
}

class QuestionnaireBlock {
 public:
  explicit QuestionnaireBlock(BlockRun& run)
      : run_(run), f_(run.frames), ins_(f_.protocol.blocks[run.block.protocol_block].instrument),
        scale_(scale_inputs(ins_)) {
    for (const io::ResponseSource* source : f_.station.responses) reach_.push_back(source->reach());
  }

  Outcome run() {
    index_ = run_.block.first_trial;
    trial_id_ = f_.trial_ids[index_];
    f_.prepare(f_.design.trials[index_].settings, "");
    f_.set_current_trial(index_);
    f_.writer.journal(data::BeginTrial{trial_id_});
    f_.scene().show(Phase::iti, false);
    load_answers();
    std::size_t item = first_unanswered();
    f_.event(trial_id_, events::QuestionnaireStart{run_.block.name, ins_.name,
                                                   static_cast<std::int64_t>(ins_.items.size()),
                                                   static_cast<std::int64_t>(item)});
    const std::int64_t start_ns = f_.clock.now_ns();
    while (item < ins_.items.size()) {
      const auto asked = ask(item, item > 0);
      if (!asked) return Outcome::quit;
      if (*asked == Asked::back) {
        --item;
        continue;
      }
      item = first_unanswered();
    }
    finish(start_ns);
    return Outcome::done;
  }

 private:
  enum class Asked { answered, back };

  void load_answers() {
    values_.assign(ins_.items.size(), std::nullopt);
    for (const auto& a : f_.check(f_.store.answers(trial_id_))) {
      const auto i = static_cast<std::size_t>(a.item_index);
      if (i < values_.size()) {
        values_[i] = a.value;
        devices_.push_back(a.device);
      }
    }
  }

  std::size_t first_unanswered() const {
    const auto it = std::find(values_.begin(), values_.end(), std::nullopt);
    return static_cast<std::size_t>(it - values_.begin());
  }

  // The scale point an item's mark starts on: its stored answer when the
  // participant came back to it, else the scale's first point.
  std::size_t start_mark(std::size_t item) const {
    if (!values_[item]) return 0;
    for (std::size_t k = 0; k < ins_.scale.size(); ++k)
      if (ins_.scale[k].value == *values_[item]) return k;
    return 0;
  }

  std::string page_text(std::size_t item, std::size_t marked, bool can_go_back) const {
    return protocol::item_page(ins_, item) + "\n\n" + controls_line(ins_, marked, can_go_back, reach_);
  }

  io::Overlay overlay(std::size_t item) const {
    io::Overlay o{Phase::instructions,
                  run_.block.name + "  " + ins_.name + " item " + std::to_string(item + 1) + "/" +
                      std::to_string(ins_.items.size()),
                  true};
    o.prompt = ins_.items[item].text;
    for (std::size_t k = 0; k < scale_.size(); ++k)
      o.answers.push_back({ins_.scale[k].label.empty() ? scale_[k].answer : ins_.scale[k].label, scale_[k].keys,
                           scale_[k].buttons});
    return o;
  }

  // One item on its page until it is answered (or the participant goes
  // back); nullopt when the session ends.
  std::optional<Asked> ask(std::size_t item, bool can_go_back) {
    Frame f;
    if (!f_.begin(f)) return std::nullopt;
    std::size_t marked = start_mark(item);
    std::string text = page_text(item, marked, can_go_back);
    if (auto shown = f_.scene().set_page(text); !shown) throw Stop{shown.error()};
    f_.scene().show(Phase::instructions, false);
    std::int64_t shown_ns = f.timing.now_ns;
    f_.event(trial_id_, data::events::Page{data::EventKind::instructions, item, text}, f.timing.predicted_display_ns);
    for (TrialWatcher* w : f_.watchers) w->item_shown(ItemFacts{index_, item, ins_, shown_ns});
    const io::Overlay shown_overlay = overlay(item);
    for (;;) {
      if (f.signal == Signal::quit) return std::nullopt;
      if (f.signal == Signal::pause) {
        if (f_.hold(Phase::instructions, trial_id_) == Outcome::quit) return std::nullopt;
        f_.scene().show(Phase::instructions, false);
        shown_ns = f_.clock.now_ns();  // keys pressed while paused do not count
        if (!f_.begin(f)) return std::nullopt;
        continue;
      }
      const ItemStep step = take_inputs(f.inputs, scale_, marked, shown_ns);
      if (step.moved && !step.chosen) {
        text = page_text(item, marked, can_go_back);
        if (auto shown = f_.scene().set_page(text); !shown) throw Stop{shown.error()};
      }
      f_.end(f, shown_overlay, false, trial_id_);
      if (step.chosen) {
        commit(item, step.chosen->first, step.chosen->second, shown_ns);
        return Asked::answered;
      }
      if (step.back && can_go_back) return Asked::back;
      if (!f_.begin(f)) return std::nullopt;
    }
  }

  // The answer, durable before the next item comes up.
  void commit(std::size_t item, std::size_t point, const io::InputEvent& in, std::int64_t shown_ns) {
    data::QuestionnaireAnswer a;
    a.session_id = f_.session_id;
    a.trial_id = trial_id_;
    a.instrument = ins_.name;
    a.item_index = static_cast<std::int64_t>(item);
    a.item_id = ins_.items[item].id;
    a.item_text = ins_.items[item].text;
    a.value = ins_.scale[point].value;
    a.label = ins_.scale[point].label;
    a.shown_ns = shown_ns;
    a.t_ns = std::max(in.t_ns, shown_ns);
    a.device = io::to_string(in.source);
    values_[item] = a.value;
    devices_.push_back(a.device);
    f_.room.status.last_response = std::to_string(a.value);
    f_.room.status.last_rt_ms = static_cast<double>(a.t_ns - shown_ns) * 1e-6;
    f_.check(f_.writer.wait_durable(f_.writer.journal(std::move(a))));
    ++f_.summary.items_answered;
  }

  // Every item answered: the subscales scored and stored, the block's trial
  // completed.
  void finish(std::int64_t start_ns) {
    data::QuestionnaireScores scores;
    const auto results = protocol::score(ins_, values_);
    for (std::size_t k = 0; k < results.size(); ++k) {
      const auto& r = results[k];
      scores.rows.push_back({f_.session_id, trial_id_, ins_.name, static_cast<std::int64_t>(k), r.name,
                             std::string(protocol::to_string(r.rule)), r.weight, static_cast<std::int64_t>(r.items),
                             static_cast<std::int64_t>(r.answered), r.raw, r.score});
    }
    if (!scores.rows.empty()) f_.writer.journal(std::move(scores));
    f_.event(trial_id_, events::QuestionnaireEnd{run_.block.name, ins_.name, static_cast<std::int64_t>(ins_.items.size())});
    data::TrialResult r;
    r.trial_id = trial_id_;
    r.onset_ns = start_ns;
    r.response_ns = f_.clock.now_ns();
    r.response = std::to_string(ins_.items.size()) + " items answered";
    r.response_device = devices_.empty() ? "none" : devices_.back();
    f_.check(f_.writer.wait_durable(f_.writer.journal(std::move(r))));
    f_.scene().show(Phase::iti, false);
    f_.set_current_trial(std::nullopt);
    f_.report_trial(index_, data::TrialStatus::completed, "");
  }

  BlockRun& run_;
  SessionFrames& f_;
  const Instrument& ins_;
  const std::vector<io::AnswerInputs> scale_;
  std::vector<io::Reach> reach_;  // the response sources at hand
  std::size_t index_ = 0;
  std::int64_t trial_id_ = 0;
  std::vector<std::optional<std::int64_t>> values_;
  std::vector<std::string> devices_;
};

class QuestionnaireKind final : public BlockKind {
 public:
  [[nodiscard]] std::string_view name() const override { return "questionnaire"; }
  [[nodiscard]] std::size_t resume_position(const protocol::PlannedBlock&, std::size_t) const override { return 0; }
  Outcome run(BlockRun& run) const override { return QuestionnaireBlock(run).run(); }
};

}  // namespace

const BlockKind& questionnaire_block_kind() {
  static const QuestionnaireKind kind;
  return kind;
}

}  // namespace curvlab::harness::runner
