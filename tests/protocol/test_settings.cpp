// The settings registry reads and writes every setting it names: a value a
// protocol may write comes back as written, a staircase reaches exactly the
// plain numbers, and the stored trial record keeps the layout the export's
// stim_* columns follow (data_schema/codebook.md).
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/harness/protocol/settings_json.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

using namespace curvlab::harness::protocol;

namespace {

// A value the setting allows that differs from its default where it can:
// the other end of its range, or its last choice.
SettingValue other_value(const SettingInfo& info) {
  switch (info.kind) {
    case SettingKind::boolean: return !std::get<bool>(*info.get(Settings{}));
    case SettingKind::integer:
    case SettingKind::integer_or_auto:
      if (!info.choices.empty()) return std::int64_t{std::stoll(std::string(info.choices.front()))};
      return static_cast<std::int64_t>(info.max);
    case SettingKind::number:
    case SettingKind::number_or_from_table: return info.max;
    case SettingKind::enumeration: return std::string(info.choices.back());
  }
  return false;
}

}  // namespace

TEST(Settings, EverySettingReadsBackTheValueApplied) {
  for (const auto& info : all_settings()) {
    SCOPED_TRACE(std::string(info.path));
    const SettingValue value = other_value(info);
    ASSERT_TRUE(check_setting(info, value).has_value());
    Settings s;
    apply_setting(s, info, value);
    if (info.path == "viewing.preset") {  // holds no value: it sets projection and eyes
      EXPECT_FALSE(info.get(s).has_value());
      EXPECT_EQ(s.viewing.projection, curvlab::renderer::Projection::native);
      EXPECT_EQ(s.viewing.eyes, curvlab::renderer::EyeSelection::dominant);
      continue;
    }
    ASSERT_TRUE(info.get(s).has_value());
    EXPECT_EQ(value_label(*info.get(s)), value_label(value));
  }
}

TEST(Settings, RadiusFromTheTableAndDefaultTableSidesHoldNoNumber) {
  const Settings defaults;
  EXPECT_EQ(std::get<std::string>(*find_setting("space.radius_m")->get(defaults)), "from_table");
  EXPECT_FALSE(find_setting("space.table_sides")->get(defaults).has_value());
  Settings s;
  apply_setting(s, *find_setting("space.radius_m"), SettingValue(std::int64_t{3}));
  EXPECT_EQ(s.space.radius_m, 3.0);
  apply_setting(s, *find_setting("space.radius_m"), SettingValue(std::string("from_table")));
  EXPECT_FALSE(s.space.radius_m.has_value());
}

TEST(Settings, MsaaIsAutoUnlessACountIsGiven) {
  const SettingInfo& msaa = *find_setting("viewing.msaa");
  EXPECT_EQ(std::get<std::string>(*msaa.get(Settings{})), "auto");
  Settings s;
  apply_setting(s, msaa, SettingValue(std::int64_t{2}));
  EXPECT_EQ(s.viewing.msaa, 2u);
  apply_setting(s, msaa, SettingValue(std::string("auto")));
  EXPECT_FALSE(s.viewing.msaa.has_value());
  for (const SettingValue& bad : {SettingValue(std::int64_t{3}), SettingValue(std::string("max")),
                                 SettingValue(2.0), SettingValue(true)})
    EXPECT_FALSE(check_setting(msaa, bad).has_value()) << value_label(bad);
}

TEST(Settings, StimulusKeysNameEveryParameterUniquely) {
  // Where the stimulus record holds a setting, under the record's own name;
  // others under the condition record's or their key.
  EXPECT_EQ(stimulus_key("stimulus.stick_sagitta_m"), "stick_sagitta_m");
  EXPECT_EQ(stimulus_key("viewing.ipd_m"), "ipd_m");
  EXPECT_EQ(stimulus_key("table.edge_m"), "table_edge_m");
  EXPECT_EQ(stimulus_key("stimulus.stick_yaw_deg"), "stick_yaw_deg");
  EXPECT_EQ(stimulus_key("space.e3_radius_m"), "e3_radius_m");
  std::set<std::string> keys;
  for (const auto& path : numeric_setting_paths()) EXPECT_TRUE(keys.insert(stimulus_key(path)).second) << path;
  // None collides with a value the record derives.
  for (const char* derived : {"radius_m", "table_sides", "tracking", "adjustment_start"})
    EXPECT_EQ(keys.count(derived), 0u) << derived;
}

TEST(Settings, StaircasesReachThePlainNumbersOnly) {
  std::vector<std::string> numbers;
  for (const auto& info : all_settings())
    if (info.kind == SettingKind::number) numbers.emplace_back(info.path);
  EXPECT_EQ(numeric_setting_paths(), numbers);
  Settings s;
  EXPECT_TRUE(set_numeric_setting(s, "stimulus.stick_sagitta_m", 0.125));
  EXPECT_EQ(s.stimulus.stick_sagitta_m, 0.125);
  EXPECT_EQ(numeric_setting(s, "stimulus.stick_sagitta_m"), 0.125);
  for (const char* other : {"space.radius_m", "stimulus.balls", "viewing.eyes", "no.such"}) {
    SCOPED_TRACE(other);
    EXPECT_FALSE(numeric_setting(s, other).has_value());
    EXPECT_FALSE(set_numeric_setting(s, other, 1.0));
  }
  EXPECT_EQ(s.stimulus.balls, Settings{}.stimulus.balls);
}

TEST(Settings, StoredStimulusRecordKeepsItsColumns) {
  Settings s;
  s.stimulus.stick_anchor = StickAnchor::table;
  Derived d;
  d.radius_m = 2.5;
  d.table_sides = 5;
  const auto j = settings_json(s, d, SettingsRecord::stimulus);
  std::vector<std::string> keys;
  for (const auto& [key, value] : j.items()) keys.push_back(key);
  EXPECT_EQ(keys, (std::vector<std::string>{"stick_sagitta_m", "table_sagitta_m", "stick_length_m",
                                            "stick_distance_m", "stick_height_m", "stick_anchor", "stick_marks",
                                            "show_stick", "show_table", "radius_m", "table_sides", "tracking",
                                            "ipd_m"}));
  EXPECT_EQ(j["stick_anchor"], "table");
  EXPECT_EQ(j["radius_m"], 2.5);
  EXPECT_EQ(j["table_sides"], 5);
  EXPECT_EQ(j["tracking"], "table-anchored");
}
