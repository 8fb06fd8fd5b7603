// What a trial showed is in its row of the trial export: the value a
// staircase or an adjustment set is the stim_<name> column of that setting
// on every trial that showed one (the staircase's `intensity` stays beside
// it), while a choice protocol's columns are what they always were.
#include "run_cli.hpp"
#include "session_db.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

using curvlab::testing::fresh_dir;
using curvlab::testing::run_cli;

namespace {

const std::string kProtocols = std::string(CURVLAB_SOURCE_DIR) + "/protocols/";

// trials.csv as rows of column → text (the exported values have no commas
// or quotes).
struct Csv {
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
};

std::vector<std::string> split(std::string line) {
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string cell;
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

Csv read_csv(const std::string& path) {
  Csv csv;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) return csv;
  csv.header = split(line);
  while (std::getline(in, line)) {
    const auto cells = split(line);
    std::map<std::string, std::string> row;
    for (std::size_t c = 0; c < csv.header.size() && c < cells.size(); ++c) row[csv.header[c]] = cells[c];
    csv.rows.push_back(std::move(row));
  }
  return csv;
}

// Runs PROTOCOL headless with --render none and exports its trial CSV.
Csv run_and_export(const std::string& protocol, const std::string& name) {
  const auto dir = fresh_dir(name);
  const auto db = (dir / "s.sqlite").string();
  const auto run = run_cli("run " + kProtocols + protocol + " --participant P01 --db " + db +
                           " --render none --quiet --json");
  EXPECT_EQ(run.exit_code, 0) << run.out;
  const auto out = (dir / "export").string();
  const auto exported = run_cli("export --db " + db + " --out " + out + " --format csv");
  EXPECT_EQ(exported.exit_code, 0) << exported.out;
  return read_csv(out + "/trials.csv");
}

}  // namespace

TEST(ShownValues, AStaircasesValueIsItsTrialsStickSagittaColumn) {
  const Csv csv = run_and_export("stick_pse_staircase.toml", "shown_staircase");
  int stepped = 0, skipped = 0, practice = 0;
  for (const auto& row : csv.rows) {
    SCOPED_TRACE("trial " + row.at("trial_index"));
    const std::string& shown = row.at("stim_stick_sagitta_m");
    if (row.at("block_name") == "practice") {
      // A choice block of the same protocol: the protocol's own bend.
      EXPECT_NE(shown, "NA");
      ++practice;
    } else if (row.at("status") == "skipped") {
      // A stopped staircase's slot showed nothing.
      EXPECT_EQ(shown, "NA");
      EXPECT_EQ(row.at("intensity"), "NA");
      ++skipped;
    } else {
      ASSERT_EQ(row.at("status"), "completed");
      ASSERT_NE(row.at("intensity"), "NA");
      ASSERT_NE(shown, "NA");
      EXPECT_NEAR(std::stod(shown), std::stod(row.at("intensity")), 1e-12);
      ++stepped;
    }
  }
  EXPECT_EQ(practice, 4);
  EXPECT_GT(stepped, 100);
  EXPECT_GT(skipped, 0);
  // The staircases moved: the column is not one planned value.
  std::map<std::string, int> values;
  for (const auto& row : csv.rows)
    if (row.at("block_name") == "main") ++values[row.at("stim_stick_sagitta_m")];
  EXPECT_GT(values.size(), 10u);
}

TEST(ShownValues, AnAdjustmentsConfirmedValueIsItsTrialsColumn) {
  // body_coherence adjusts stimulus.stick_distance_m.
  const Csv csv = run_and_export("body_coherence.toml", "shown_adjustment");
  ASSERT_EQ(csv.rows.size(), 48u);
  for (const auto& row : csv.rows) {
    SCOPED_TRACE("trial " + row.at("trial_index"));
    ASSERT_EQ(row.at("status"), "completed");
    ASSERT_NE(row.at("response"), "timeout");
    // The response is the confirmed value as "%.9g" text.
    EXPECT_NEAR(std::stod(row.at("stim_stick_distance_m")), std::stod(row.at("response")), 1e-8);
    EXPECT_NE(row.at("stim_adjustment_start"), "NA");
  }
}

TEST(ShownValues, AChoiceProtocolsColumnsAreUnchanged) {
  const Csv csv = run_and_export("demo.toml", "shown_choice");
  std::vector<std::string> stim;
  for (const auto& name : csv.header)
    if (name.rfind("stim_", 0) == 0) stim.push_back(name);
  EXPECT_EQ(stim, (std::vector<std::string>{"stim_stick_sagitta_m", "stim_table_sagitta_m", "stim_stick_length_m",
                                            "stim_stick_distance_m", "stim_stick_height_m", "stim_stick_anchor",
                                            "stim_stick_marks", "stim_show_stick", "stim_show_table",
                                            "stim_radius_m", "stim_table_sides", "stim_tracking", "stim_ipd_m"}));
  ASSERT_EQ(csv.rows.size(), 8u);
  for (const auto& row : csv.rows) {
    EXPECT_EQ(std::stod(row.at("stim_stick_sagitta_m")), 0.0);
    EXPECT_EQ(std::stod(row.at("stim_stick_distance_m")), 1.0);
    EXPECT_EQ(row.at("intensity"), "NA");
  }
}
