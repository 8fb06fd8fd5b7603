// Questionnaire instruments (docs/questionnaires.md): items answered on one
// response scale in a questionnaire block, and their scoring into subscales.
// The Simulator Sickness Questionnaire is built in (ssq_instrument); a
// protocol defines its own under [instruments.<name>]. Pure data and pure
// functions: the loader fills them, the runner shows and stores the items,
// scoring here is what the runner stores when a block ends.
#pragma once

#include "curvlab/harness/protocol/diagnostic.hpp"

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::protocol {

// One point of the response scale and the controls that choose it: a digit
// key (the value's own digit where every value is 0–9, else the point's
// position from 1) and a button box's button hid_<position from 1>.
struct ScalePoint {
  std::int64_t value = 0;
  std::string label;
  std::string key;
  std::string button;
};

struct QuestionnaireItem {
  std::string id;
  std::string text;
  bool reversed = false;  // scored as (lowest + highest value) − value
};

enum class ScoreRule { sum, mean };
std::string_view to_string(ScoreRule r);

// weight × (sum or mean) of the items' scored values. An item may be listed
// more than once (the SSQ's total counts items of two subscales twice).
struct Subscale {
  std::string name;
  std::vector<std::size_t> items;  // indices into Instrument::items
  ScoreRule rule = ScoreRule::sum;
  double weight = 1.0;
};

struct Instrument {
  std::string name;   // "ssq", or the protocol's [instruments.<name>]
  std::string title;  // shown above each item
  std::vector<QuestionnaireItem> items;
  std::vector<ScalePoint> scale;  // in the order shown
  std::vector<Subscale> subscales;
  SourcePos pos;
};

// The Simulator Sickness Questionnaire: 16 symptoms rated 0–3 (None,
// Slight, Moderate, Severe), scored as Kennedy, Lane, Berbaum & Lilienthal
// (1993), Int. J. Aviation Psychology 3(3):203–220, Table 5: Nausea
// (items 1, 6, 7, 8, 9, 15, 16) × 9.54, Oculomotor (1, 2, 3, 4, 5, 9, 11)
// × 7.58, Disorientation (5, 8, 10, 11, 12, 13, 14) × 13.92, Total (the sum
// of the three raw sums) × 3.74.
const Instrument& ssq_instrument();
inline constexpr std::string_view kSsqName = "ssq";

// Fills each scale point's key and button from its value and position.
void bind_scale_controls(std::vector<ScalePoint>& scale);

// The value an item's answer counts with: reversed items mirrored on the scale.
std::int64_t scored_value(const Instrument& ins, std::size_t item, std::int64_t value);

struct SubscaleResult {
  std::string name;
  ScoreRule rule = ScoreRule::sum;
  double weight = 1.0;
  std::size_t items = 0;     // items counted (with repeats)
  std::size_t answered = 0;  // of which answered
  std::optional<double> raw;    // sum or mean; only when every item was answered
  std::optional<double> score;  // weight × raw
};

// Every subscale of `ins` for `values` (one per item, nullopt: unanswered),
// in the instrument's order.
std::vector<SubscaleResult> score(const Instrument& ins, const std::vector<std::optional<std::int64_t>>& values);

// The page an item is shown as: the title, the item's text, then each scale
// point's key and label, e.g. "Fatigue\n\n0 None   1 Slight   2 Moderate   3 Severe".
std::string item_page(const Instrument& ins, std::size_t item);

}  // namespace curvlab::harness::protocol
