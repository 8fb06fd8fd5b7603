#include "session_records.hpp"

#include "curvlab/harness/protocol/judgement.hpp"
#include "curvlab/harness/protocol/settings_json.hpp"
#include "curvlab/harness/runner/session.hpp"
#include "curvlab/harness/runner/stimulus.hpp"

#include <cstdio>
#include <cstdlib>

namespace curvlab::harness::runner {

using protocol::PlannedTrial;
using protocol::Protocol;

const protocol::Block& block_of(const Protocol& p, const PlannedTrial& t) {
  if (t.protocol_block < p.blocks.size()) return p.blocks[t.protocol_block];
  std::fprintf(stderr, "curvlab: planned trial %zu is of block %zu, which protocol %s lacks\n", t.index,
               t.protocol_block, p.file.c_str());
  std::abort();
}

std::string staircase_key(const Protocol& p, const PlannedTrial& t, const std::string& track) {
  const auto& b = block_of(p, t);
  std::string key = t.block + ":";
  if (protocol::block_cells(p, b).size() > 1) key += "cell" + std::to_string(t.cell) + ":";
  return key + track;
}

std::optional<data::StepPosterior> step_posterior(const std::optional<protocol::PosteriorSummary>& p) {
  if (!p) return std::nullopt;
  return data::StepPosterior{p->pse_mean, p->pse_sd,    p->slope_mean,  p->slope_sd,
                             p->lapse_mean, p->lapse_sd, p->entropy_nats};
}

data::Pose16 pose16(const geometry::Isometry& iso) {
  data::Pose16 a{};
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) a[static_cast<std::size_t>(c * 4 + r)] = iso.m[c][r];
  return a;
}

std::vector<data::BlockPlan> block_plans(const Protocol& p, const protocol::Design& d) {
  std::vector<data::BlockPlan> out;
  for (const auto& b : d.blocks) {
    data::BlockPlan bp;
    bp.name = b.name;
    bp.is_practice = b.practice;
    Json settings{{"instructions", b.instructions}, {"break_min_ms", b.break_min_ms}};
    bp.settings_json = settings.dump();
    for (std::size_t k = 0; k < b.trial_count; ++k) {
      const auto& t = d.trials.at(b.first_trial + k);
      bp.trials.push_back({conditions_json(p, t), stimulus_json(p, t)});
    }
    out.push_back(std::move(bp));
  }
  return out;
}

std::string conditions_json(const Protocol& p, const PlannedTrial& t) {
  Json j;
  for (const auto& [factor, label] : t.levels) j[factor] = label;
  const auto& s = t.settings;
  auto add = [&](const char* key, const std::string& v) {
    if (!j.contains(key)) j[key] = v;
  };
  add("space", std::string(geometry::to_string(s.space.kind)));
  add("view", view_name(s));
  add("projection", std::string(renderer::to_string(s.viewing.projection)));
  add("eyes", std::string(renderer::to_string(s.viewing.eyes)));
  add("judged", std::string(judged_kind(s).name()));
  const auto& judgement = block_of(p, t).judgement;
  for (const auto& [name, value] : judgement.type->conditions(judgement, t)) add(name.c_str(), value);
  return j.dump();
}

namespace {

// The stimulus record of settings `s`. The parameter of a judgement that
// sets it on each trial (a staircase's, an adjustment's) is stored under its
// own key: its value when the trial `shown` it, null in the plan, where the
// value is not known yet (a staircase's next value depends on the answers).
std::string stimulus_record(const Protocol& p, const PlannedTrial& t, const protocol::Settings& s,
                            const protocol::Derived& d, bool shown) {
  Json j = protocol::settings_json(s, d, protocol::SettingsRecord::stimulus);
  if (t.adjustment_start) j["adjustment_start"] = *t.adjustment_start;
  const std::string& parameter = block_of(p, t).judgement.parameter;
  if (!parameter.empty()) {
    const auto value = shown ? protocol::numeric_setting(s, parameter) : std::nullopt;
    j[protocol::stimulus_key(parameter)] = value ? Json(*value) : Json(nullptr);
  }
  return j.dump();
}

}  // namespace

std::string stimulus_json(const Protocol& p, const PlannedTrial& t) {
  return stimulus_record(p, t, t.settings, t.derived, false);
}

std::string shown_stimulus_json(const Protocol& p, const PlannedTrial& t, const protocol::Settings& shown) {
  // The parameter may move a derived value (table.edge_m the radius).
  const auto derived = protocol::derive(shown);
  return stimulus_record(p, t, shown, derived ? *derived : t.derived, true);
}

}  // namespace curvlab::harness::runner
