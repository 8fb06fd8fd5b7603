#include "curvlab/harness/protocol/design.hpp"

#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/latin_square.hpp"
#include "curvlab/harness/protocol/random.hpp"

namespace curvlab::harness::protocol {

std::int64_t Design::estimated_duration_ms() const {
  std::int64_t total = 0;
  for (const auto& t : trials) {
    total += t.settings.timeline.total_ms();
    if (t.break_before) total += blocks.at(t.block_position).break_min_ms;
  }
  return total;
}

std::vector<std::vector<std::size_t>> block_cells(const Protocol& p, const Block& b) {
  std::vector<std::vector<std::size_t>> per_factor;
  for (const auto& f : p.factors) {
    auto it = b.levels.find(f.name);
    if (it != b.levels.end()) {
      per_factor.push_back(it->second);
    } else {
      std::vector<std::size_t> all(f.levels.size());
      for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
      per_factor.push_back(all);
    }
  }
  std::vector<std::vector<std::size_t>> cells{{}};
  for (const auto& choices : per_factor) {
    std::vector<std::vector<std::size_t>> next;
    next.reserve(cells.size() * choices.size());
    for (const auto& c : cells)
      for (std::size_t lvl : choices) {
        auto e = c;
        e.push_back(lvl);
        next.push_back(std::move(e));
      }
    cells = std::move(next);
  }
  return cells;
}

namespace {

std::vector<std::size_t> block_run_order(const Protocol& p, std::uint64_t participant, Engine& rng,
                                         std::optional<std::size_t>& row_used) {
  std::vector<std::size_t> practice, main;
  for (std::size_t i = 0; i < p.blocks.size(); ++i)
    (p.blocks[i].practice ? practice : main).push_back(i);
  std::vector<std::size_t> order = practice;
  switch (p.block_order) {
    case BlockOrder::fixed:
      break;
    case BlockOrder::random:
      shuffle(main, rng);
      break;
    case BlockOrder::latin_square: {
      const Square sq = p.square.empty() ? williams_design(main.size()) : p.square;
      const std::size_t row = row_for_participant(sq, participant);
      row_used = row;
      std::vector<std::size_t> reordered;
      for (std::size_t k : sq[row]) reordered.push_back(main[k]);
      main = reordered;
      break;
    }
  }
  order.insert(order.end(), main.begin(), main.end());
  return order;
}

}  // namespace

Design expand_design(const Protocol& p, std::uint64_t participant) {
  Design d;
  d.protocol_seed = p.seed;
  d.participant = participant;
  d.seed = participant_seed(p.seed, participant, p.seed_per_participant);
  Engine rng(d.seed);

  const auto order = block_run_order(p, participant, rng, d.counterbalance_row);
  for (std::size_t pos = 0; pos < order.size(); ++pos) {
    const Block& b = p.blocks[order[pos]];
    const auto cells = block_cells(p, b);
    const Settings base = p.block_settings(b);

    const JudgementType& type = *b.judgement.type;
    // A play block is one stretch of play in its first cell, a
    // questionnaire block one run through its instrument's items: one
    // planned trial that stands for the block (its status says whether it
    // ended).
    const bool one_trial = b.kind == "play" || b.kind == "questionnaire";
    const std::vector<DesignSlot> slots = one_trial ? std::vector<DesignSlot>{DesignSlot{}} : type.slots(b, cells.size(), rng);

    PlannedBlock pb;
    pb.name = b.name;
    pb.kind = b.kind;
    pb.protocol_block = order[pos];
    pb.practice = b.practice;
    pb.first_trial = d.trials.size();
    pb.trial_count = slots.size();
    pb.instructions = b.instructions;
    pb.break_min_ms = b.break_min_ms;
    d.blocks.push_back(pb);

    for (std::size_t k = 0; k < slots.size(); ++k) {
      PlannedTrial t;
      t.index = d.trials.size();
      t.block_position = pos;
      t.protocol_block = order[pos];
      t.block = b.name;
      t.practice = b.practice;
      t.trial_in_block = k;
      t.repetition = slots[k].repetition;
      t.cell = slots[k].cell;
      t.staircase = slots[k].staircase;
      t.judgement = &type;
      t.settings = base;
      const auto& cell = cells[slots[k].cell];
      for (std::size_t f = 0; f < p.factors.size(); ++f) {
        const Factor& factor = p.factors[f];
        const Level& level = factor.levels[cell[f]];
        t.levels.emplace_back(factor.name, level.label);
        if (const auto* info = find_setting(factor.sets)) apply_setting(t.settings, *info, level.value);
      }
      if (!one_trial) type.plan_trial(b.judgement, t, rng);
      const auto derived = derive(t.settings);
      t.derived = derived ? derived.value() : Derived{};
      t.break_before = b.break_every_trials > 0 && k > 0 &&
                       k % static_cast<std::size_t>(b.break_every_trials) == 0;
      d.trials.push_back(std::move(t));
    }
  }
  return d;
}

}  // namespace curvlab::harness::protocol
