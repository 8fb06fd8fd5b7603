// A trial's settings as JSON, written only here: each value read through the
// settings registry (settings.hpp), enumerations by name, the space's radius
// and virtual table as derive() resolved them. A record names the settings
// it holds, in a fixed order, because something downstream reads each one
// (settings_json.cpp); a new setting joins a record by a line there.
// Pure; thread-safe.
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/protocol/settings.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <string_view>

namespace curvlab::harness::protocol {

enum class SettingsRecord {
  // What the runner stores as trials.stimulus (data_schema/codebook.md),
  // exported as stim_<name> columns in this order.
  stimulus,
  // Everything a participant sees in a trial: `curvlab design --json` lists
  // it per trial, and trials with equal levels and equal settings are one
  // condition (`curvlab preview`'s panels).
  condition,
};

nlohmann::ordered_json settings_json(const Settings& s, const Derived& d, SettingsRecord record);

// The key under which the stimulus record holds a setting's value: its own
// key where the record names it ("stimulus.stick_sagitta_m" →
// "stick_sagitta_m"), else the condition record's ("table.edge_m" →
// "table_edge_m"), else the part after the section ("space.e3_radius_m" →
// "e3_radius_m"). A staircase's or an adjustment's parameter is stored
// under it on every trial (the export's stim_<key> column).
std::string stimulus_key(std::string_view path);

}  // namespace curvlab::harness::protocol
