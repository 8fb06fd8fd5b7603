// What a protocol should be warned about before participant hours
// (`curvlab validate`, `preview` and `predict`): a condition whose stimulus
// leaves an eye's field of view, one the human observer model does not
// cover, a staircase that cannot converge inside its range. Pure functions
// of the protocol (and of a prediction), from the geometry the runner and
// the perception model share (stimulus.hpp, geometry/perception.hpp).
#pragma once

#include "curvlab/harness/protocol/protocol.hpp"
#include "curvlab/harness/runner/predict.hpp"

#include <string>
#include <string_view>
#include <vector>

namespace curvlab::harness::runner {

enum class StimulusWarningKind { out_of_view, model_range, no_convergence };

std::string_view to_string(StimulusWarningKind kind);  // "out_of_view", "model_range", "no_convergence"

struct StimulusWarning {
  StimulusWarningKind kind = StimulusWarningKind::out_of_view;
  std::string block;
  std::string condition;  // "space=S3 projection=tourist"
  std::string message;    // a whole sentence, block and condition named
};

// A field of view the stimulus is checked against: symmetric, per eye.
struct FieldOfView {
  std::string name;  // "a headset's default 90°×90°"
  double half_horizontal_rad = 0.0;
  double half_vertical_rad = 0.0;
};
// The default headset's (90° × 90° per eye) and the protocol's (90°
// horizontally at its resolution's aspect, as the headless display and
// `preview` draw it); one entry when they are the same.
std::vector<FieldOfView> fields_of_view(const protocol::Protocol& p);

// The human model's range of validity: the apparent-frontal-plane data it
// rests on span about ±16° of eccentricity from the fixated point
// (docs/runner.md, "The human observer").
inline constexpr double kHumanModelEccentricityDeg = 16.0;

// Per distinct condition of the protocol (practice included), seen from
// where the headless participant stands (standing_head): each judged point
// (the stick's ends and middle, the table's edge midpoints and centre)
// outside an eye's field of view, naming the eye, the point and its angle;
// and binocular conditions whose judged points lie beyond the human model's
// eccentricity range. At most one warning of each kind per condition.
std::vector<StimulusWarning> stimulus_warnings(const protocol::Protocol& p);

// The staircases whose target lies outside their [min, max] (predict.hpp,
// StaircasePrediction): the track would run into its limit instead of
// converging.
std::vector<StimulusWarning> convergence_warnings(const std::vector<StaircasePrediction>& staircases);

// All of the above for the default human observer: what validate, preview
// and predict print.
std::vector<StimulusWarning> protocol_warnings(const protocol::Protocol& p);

}  // namespace curvlab::harness::runner
