// Checks of the protocol's design as a whole, once every section has been
// read: how many cells and trials it makes, and what can only be checked on
// a resolved factor-level combination.
#include "loader_impl.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <set>
#include <sstream>

namespace curvlab::harness::protocol {
namespace {

namespace tr = toml_reader;
using tr::type_name;

constexpr std::size_t kMaxCells = 100000;
constexpr std::size_t kMaxTrials = 1000000;

}  // namespace

void Loader::check_design(const Protocol& p, const toml::table& root) {
  std::size_t total = 0;
  for (std::size_t bi = 0; bi < p.blocks.size(); ++bi) {
    const Block& b = p.blocks[bi];
    const std::string bp = root.contains("blocks") ? "blocks[" + std::to_string(bi + 1) + "]" : "blocks";
    std::size_t cells = 1;
    for (const auto& f : p.factors) {
      const auto it = b.levels.find(f.name);
      const std::size_t n = it == b.levels.end() ? f.levels.size() : it->second.size();
      cells = n == 0 ? 0 : (cells > kMaxCells ? cells : cells * n);
    }
    if (cells > kMaxCells) {
      error(b.pos, bp, "the block crosses more than " + std::to_string(kMaxCells) + " factor-level combinations");
      return;
    }
    const std::size_t trials = cells * b.judgement.type->trials_per_cell(b);
    if (trials == 0) error(b.pos, bp, "the block has zero trials");
    total += trials;
    if (total > kMaxTrials) {
      error(b.pos, bp, "the session would exceed " + std::to_string(kMaxTrials) + " trials");
      return;
    }
    check_cells(p, b, bp);
  }
}

void Loader::check_cells(const Protocol& p, const Block& b, const std::string& bp) {
  // Where each setting got its value: position and the field as written.
  std::map<std::string, std::pair<SourcePos, std::string>> base_origin;
  for (const auto& o : p.session_overrides) base_origin[o.path] = {o.pos, o.path};
  const bool explicit_blocks = bp != "blocks";
  for (const auto& o : b.overrides)
    base_origin[o.path] = {o.pos, explicit_blocks ? bp + "." + o.path : o.path};
  const Settings base = p.block_settings(b);
  std::set<std::pair<std::string, std::string>> reported;
  for (const auto& cell : block_cells(p, b)) {
    Settings s = base;
    auto origin = base_origin;
    std::string where;
    for (std::size_t f = 0; f < p.factors.size(); ++f) {
      const Level& l = p.factors[f].levels[cell[f]];
      if (const auto* info = find_setting(p.factors[f].sets)) {
        apply_setting(s, *info, l.value);
        origin[p.factors[f].sets] = {l.pos, "factors." + p.factors[f].name + ".levels[" +
                                                   std::to_string(cell[f] + 1) + "]"};
      }
      where += (where.empty() ? "" : ", ") + p.factors[f].name + " = " + l.label;
    }
    const std::string suffix = where.empty() ? "" : " (in " + b.name + " with " + where + ")";
    const auto report = [&](const std::string& path, const std::string& msg) {
      if (!reported.insert({path, msg}).second) return;
      const auto it = origin.find(path);
      if (it != origin.end()) error(it->second.first, it->second.second, msg + suffix);
      else error(b.pos, bp, msg + suffix);
    };
    check_settings(s, report);
    // The values the judgement can reach must be possible too:
    // check both ends of every range, reported at the judgement.
    const std::string& param = b.judgement.parameter;
    const std::vector<double> ends = b.judgement.type->reachable_values(b.judgement);
    if (param.empty() || ends.empty()) continue;
    const std::string jfield = (b.judgement.pos.line == p.judgement.pos.line &&
                                b.judgement.pos.column == p.judgement.pos.column)
                                   ? "judgement"
                                   : bp + ".judgement";
    for (double v : ends) {
      Settings reached = s;
      set_numeric_setting(reached, param, v);
      check_settings(reached, [&](const std::string& path, const std::string& msg) {
        const std::string full = msg + " when " + param + " reaches " +
                                 value_label(SettingValue(std::in_place_type<double>, v));
        if (reported.insert({path, full}).second) error(b.judgement.pos, jfield, full + suffix);
      });
    }
  }
}

template <typename Report>
void Loader::check_settings(const Settings& s, const Report& report) {
  if (const auto derived = derive(s); !derived)
    report(s.space.table_sides > 0 ? "space.table_sides" : "space.kind", derived.error().message);
  if (s.stimulus.stick_anchor == StickAnchor::head && s.stimulus.stick_distance_m < 0.1)
    report("stimulus.stick_distance_m",
           "a head-anchored stick must be at least 0.1 m from the eyes, found " +
               value_label(SettingValue(std::in_place_type<double>, s.stimulus.stick_distance_m)));
  if (std::abs(s.stimulus.stick_sagitta_m) >= s.stimulus.stick_length_m / 2)
    report("stimulus.stick_sagitta_m", "expected |sagitta| < stick_length_m / 2 = " +
                                           number_label(s.stimulus.stick_length_m / 2) + ", got " +
                                           number_label(s.stimulus.stick_sagitta_m));
}

}  // namespace curvlab::harness::protocol
