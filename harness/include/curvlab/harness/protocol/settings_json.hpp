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

}  // namespace curvlab::harness::protocol
