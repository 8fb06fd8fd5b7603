// A loaded, validated protocol: plain data, no file format in sight. The
// loader (loader.hpp) is the only code that knows TOML; the design expander,
// the staircase and the runner work from this struct.
#pragma once

#include "curvlab/geometry/table.hpp"
#include "curvlab/harness/protocol/diagnostic.hpp"
#include "curvlab/harness/protocol/questionnaire.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/harness/result.hpp"

#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace curvlab::harness::protocol {

struct Metadata {
  std::string name;
  std::string version;
  std::string description;
};

// One value written somewhere in the protocol, with where it was written.
struct SettingOverride {
  std::string path;  // registry path, e.g. "viewing.preset"
  SettingValue value;
  SourcePos pos;
};

struct Level {
  std::string label;
  SettingValue value;
  SourcePos pos;
};

// A factor varies one setting (`sets`) over its levels, or, with `sets`
// empty, only labels trials (for example a between-subject grouping).
struct Factor {
  std::string name;
  std::string sets;
  std::string description;
  std::vector<Level> levels;
  SourcePos pos;
};

// The family of judgement types and what a type keeps of its own table
// (judgement.hpp).
class JudgementType;
class JudgementSpec;

struct ResponseOption {
  std::string value;  // stored in the data, e.g. "convex"
  std::string label;  // shown on the in-headset panel
  std::vector<std::string> keys;
  std::vector<std::string> buttons;
};

struct Judgement {
  // The registered type; null only in a protocol that failed to load.
  const JudgementType* type = nullptr;
  std::string prompt;
  // After each answer, the answer given (its label) or "No answer" is shown
  // on the participant's panel through the inter-trial interval.
  bool feedback = false;
  std::vector<ResponseOption> options;  // types answered by choosing: the answers
  std::string parameter;                // types that vary a numeric setting: its path
  std::shared_ptr<const JudgementSpec> spec;  // the rest, the type's own; shared by copies
  SourcePos pos;
};

enum class RandomizeMode { none, shuffle, shuffle_within_repetition };
enum class BlockOrder { fixed, latin_square, random };
std::string_view to_string(RandomizeMode m);
std::string_view to_string(BlockOrder o);

// What a play block plays (kind "play"; docs/billiards.md): curved-space
// billiards at the table until the time, the shot limit or the last ball.
struct PlaySettings {
  double duration_s = 300.0;
  int shots = 0;               // 0: no limit
  bool until_all_pocketed = true;
  int rack = 15;               // object balls in the rack
  // Physics parameters by name (geometry/billiards.hpp), checked at load.
  std::vector<std::pair<std::string, double>> physics;
};

struct Block {
  std::string name;
  // What the block's frames show (the runner's block kinds): "trials", a
  // list of judged trials; "play", billiards; "questionnaire", an
  // instrument's items.
  std::string kind = "trials";
  PlaySettings play;  // kind "play" only
  // Kind "questionnaire" only: the instrument its items come from (the
  // built-in SSQ or one of Protocol::instruments), as loaded.
  Instrument instrument;
  bool practice = false;
  int repetitions = 1;
  RandomizeMode randomize = RandomizeMode::shuffle;
  // Factor name → indices of the levels this block uses (absent: all levels).
  std::map<std::string, std::vector<std::size_t>> levels;
  std::vector<SettingOverride> overrides;  // applied on top of the session's
  Judgement judgement;                     // the session's unless overridden
  std::vector<std::string> instructions;   // pages shown before the block
  int break_every_trials = 0;              // 0: no breaks inside the block
  std::string break_text;
  std::int64_t break_min_ms = 0;
  SourcePos pos;
};

// The block kinds a protocol may name, "trials" first (the default).
const std::vector<std::string>& block_kind_names();

// The [calibration] section: the physical table calibrated by touching its
// corners with the participant's devices as the session's first step
// (runner/calibration.hpp; docs/devices.md, "Physical-table calibration").
// Session level only: the table does not change between blocks.
struct CalibrationStep {
  bool at_start = false;  // calibrate before the session (desktop and xr runs)
  // The touching tip in the right controller's grip frame, metres.
  std::array<double, 3> tip_offset_m{0.0, 0.0, 0.0};
  double max_residual_mm = 15.0;  // a touch farther from its fitted corner is refused
};

struct Protocol {
  std::string file;
  // The [responses] section: HID mapping files whose devices answer when a
  // person does (desktop and xr runs; docs/devices.md), as written, relative
  // to the protocol file's folder.
  std::vector<std::string> hid_mappings;
  std::string text;  // the TOML it was loaded from (sessions store it)
  Metadata meta;
  std::vector<SettingOverride> session_overrides;
  std::vector<Factor> factors;
  Judgement judgement;
  std::vector<Block> blocks;  // in file order
  // The [instruments.<name>] tables: questionnaires the protocol defines.
  std::vector<Instrument> instruments;
  std::uint64_t seed = 0;
  bool seed_per_participant = true;
  BlockOrder block_order = BlockOrder::fixed;
  // Explicit counterbalancing square: rows of indices into the non-practice
  // blocks (file order). Empty: a Williams design is generated.
  std::vector<std::vector<std::size_t>> square;
  std::vector<std::string> instructions_start, instructions_end;
  std::string backend_preferred = "headless";
  int refresh_hz = 90;
  int resolution_width = 1024, resolution_height = 1024;
  CalibrationStep calibration;
  // The [lsl] section: the session streams its markers, poses and gaze to
  // the Lab Streaming Layer (as `curvlab run --lsl` does; docs/lsl.md).
  bool lsl_outlets = false;

  // The session's settings: defaults with the session sections applied.
  [[nodiscard]] Settings session_settings() const;
  // The settings of one block before any factor level is applied.
  [[nodiscard]] Settings block_settings(const Block& b) const;
  [[nodiscard]] const Factor* find_factor(const std::string& name) const;
};

// Values derived from the settings of one trial (paper, "Construction of the
// billiards tables": the table's edge matches the physical edge, ρ = L / s).
struct Derived {
  double radius_m = 0.0;
  int table_sides = 0;
  double side_rad = 0.0;
  double table_circumradius_m = 0.0;
  double table_apothem_m = 0.0;
};

// The derived values, or why the settings describe an impossible table
// (bad_input).
Result<Derived> derive(const Settings& s);
// The virtual table the settings describe, or why there is none (bad_input).
Result<geometry::TableShape> table_shape(const Settings& s);

}  // namespace curvlab::harness::protocol
