// A trial's world and stimulus, from its resolved settings: the space and the
// virtual table (paper, "Construction of the billiards tables"), where the
// stick goes at onset (relative to the head or to the table), the scene the
// renderer draws through the trial's phases, and the quantity the simulated
// observer judges (DESIGN.md §5). What is shown and judged is asked of the
// trial's stimulus kinds (stimulus_kind.hpp).
#pragma once

#include "curvlab/harness/result.hpp"
#include "curvlab/harness/runner/phase.hpp"
#include "curvlab/harness/runner/stimulus_kind.hpp"

#include "curvlab/geometry/calibration.hpp"
#include "curvlab/geometry/perception.hpp"
#include "curvlab/geometry/table.hpp"
#include "curvlab/geometry/tracking.hpp"
#include "curvlab/geometry/tube.hpp"
#include "curvlab/harness/protocol/settings.hpp"
#include "curvlab/renderer/scene.hpp"
#include "curvlab/renderer/view.hpp"

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace curvlab::harness::runner {

Result<World> make_world(const protocol::Settings& s);

// The physical table of the tracking code, from calibration (centre, yaw)
// and the protocol (edge, height).
geometry::PhysicalTable physical_table(const protocol::Settings& s,
                                       const std::optional<geometry::PhysicalTableFit>& calibration);

// The default calibration of a headless run: a table of the protocol's edge
// and height centred at the lab origin, yaw 0.
geometry::PhysicalTableFit nominal_calibration(const protocol::Settings& s);

// The calibration as stored with a session (sessions.table_calibration), and
// back; parsing names what is missing or out of range (a non-finite value, a
// centre outside the lab volume of lab_volume.hpp), after `FILE:LINE: ` when
// the text is a file's.
std::string calibration_json(const geometry::PhysicalTableFit& fit);
Result<geometry::PhysicalTableFit> parse_calibration_json(const std::string& text, const std::string& file = "");

// The placement at onset: each of the trial's kinds takes its share from
// the head at onset (StimulusKind::place).
Placement place_stimulus(const World& world, const protocol::Settings& s,
                         const geometry::Isometry& head_at_onset);

// The virtual head at onset of a participant standing at the nominal table
// (the headless backend's standing pose, at its default eye height, before
// any sway), placed by the protocol's tracking algorithm: where the headless
// runner's participant stands, and where `curvlab predict` and `curvlab
// preview` view the stimulus from.
geometry::Isometry standing_head(const World& world, const protocol::Settings& s);

// What the perception model is given for the trial's projection and eyes
// (renderer::perceived_preset).
geometry::ViewPreset perceived_preset(const protocol::Settings& s);
renderer::ViewSettings view_settings(const protocol::Settings& s, renderer::Eye dominant);
// The preset the trial's projection and eyes are named by: "tourist",
// "native", "monocular" (native, one eye) or "custom" (tourist, one eye).
std::string view_name(const protocol::Settings& s);

// The points a judgement rests on (the judged kind's, judged_kind): the
// stick's ends and middle (end, middle, end), or the table's edge midpoints
// followed by its (possibly raised) centre.
std::vector<geometry::Point> judged_points(const World& world, const protocol::Settings& s,
                                           const Placement& placement);

// The perceived signed sagitta of the judged object for the ideal geometer
// whose nose is at `head` (perception.hpp): the stick's bow toward the viewer, or the
// table top's rise of its centre above the plane of its edge midpoints.
// One eye: 0 (no disparity, DESIGN.md §5).
double perceived_sagitta_m(const World& world, const protocol::Settings& s,
                           const Placement& placement, const geometry::Isometry& head);
// The same sagitta from the judged points as perceived (judged_points'
// order) and the map that perceived them, which the table's judgement also
// asks where its flat centre and its up are seen (the human observer's,
// percept.hpp, perceives the judged points together).
double perceived_sagitta_with(const World& world, const protocol::Settings& s, std::vector<geometry::Vec3> judged_seen,
                              const std::function<geometry::Vec3(const geometry::Point&)>& seen);
// How many of the points the judgement rests on (the stick's ends and
// middle; the table's edge midpoints and centre) a tourist's two lines of
// sight reach only by diverging or running parallel: in S3 beyond the
// quarter circumference ρπ/2 the eyes would have to turn outward, and the
// model meets the lines behind the eyes (perception.hpp), where a few
// hundredths of a pixel of disparity move a point by metres. 0 in native and
// monocular views.
struct SightLineCount {
  int diverging = 0;  // judged points seen only along diverging or parallel lines
  int points = 0;     // judged points
};
SightLineCount diverging_sight_lines(const World& world, const protocol::Settings& s, const Placement& placement,
                                     const geometry::Isometry& head);
// The same for the physical stimulus alone (the null observer).
double physical_sagitta_m(const protocol::Settings& s);

// The scene of one trial: the objects of the stimulus kinds the trial shows
// (stimulus_kind.hpp), a prompt panel, a fixation mark and a page of text,
// with visibility switched per phase. The one builder of what participants
// see: sessions, `replay`, `preview` and `curvlab render` (viewed_scene
// below) all draw it. Not thread-safe.
class TrialScene {
 public:
  // `prompt`: the response panel's text, the question and its answers
  // (response_panel_text). The panels are head-locked (renderer
  // HeadPanelLayout) with text s.viewing.text_height_deg high, drawn at
  // px_per_deg texels per degree (the display's pixels per degree).
  static Result<TrialScene> build(const World& world, const protocol::Settings& s, const std::string& prompt,
                                  const std::string& font_path, double px_per_deg = kPanelPxPerDeg);
  // Texels per degree where the display's density is not known.
  static constexpr double kPanelPxPerDeg = 16.0;
  // Visibility for a phase and the stimulus placement (fixed at onset).
  void show(Phase phase, bool stimulus_during_response);
  void place(const Placement& placement, const geometry::Isometry& head_at_onset);
  // A changed stimulus during the trial (method of adjustment): the stick's
  // shape and pose and the cloth's convexity follow the settings.
  void set_stimulus(const protocol::Settings& s, const Placement& placement);
  // Every frame, before it is drawn: the kinds follow the clock and the
  // frame's curved-space poses (a rolling ball, a cue in a hand).
  void update(std::int64_t t_ns, const FramePoses& poses);
  // A page of text fixed to the head (instructions, breaks, questions).
  Result<Done> set_page(const std::string& text);
  // The page's panel with `text` shown now, whatever the phase (an answer's
  // feedback); the next show() hides it again.
  Result<Done> show_page(const std::string& text);
  renderer::Scene& scene() { return scene_; }
  [[nodiscard]] const renderer::Scene& scene() const { return scene_; }

 private:
  World world_;
  renderer::Scene scene_;
  std::string font_path_;
  renderer::HeadPanelLayout page_layout_;
  std::size_t prompt_ = 0, fixation_ = 0, page_ = 0;
  std::vector<std::unique_ptr<StimulusObjects>> stimuli_;
  std::string page_text_;
};

// The scenes `curvlab render`, the renderer's golden images and the
// benchmarks draw, built by TrialScene from protocol settings (scene_settings)
// so that what is tested is what participants see: the `stick` alone in
// front of the head, the `table`, or `billiards` (the table, balls and a
// stick across it), shown as in a trial's response window (stimulus and
// prompt); `tiling` is the space's honeycomb, a debug scene of the renderer's.
enum class SceneKind { stick, table, billiards, tiling };
std::optional<SceneKind> parse_scene_kind(std::string_view text);
std::string_view to_string(SceneKind kind);

// Protocol settings `base` (the space, its radius, the stick's bend and
// marks, …) with what a scene kind shows.
protocol::Settings scene_settings(SceneKind kind, protocol::Settings base);

// Where the viewer stands: the stick scene's head at the origin; the table
// scenes' eyes eye_height_m above the floor outside edge 0, looking at the
// table's centre. yaw_rad turns the head left (+) from facing the stimulus,
// after the stimulus was placed.
struct SceneView {
  double eye_height_m = 1.55;
  double yaw_rad = 0.0;
  double panel_px_per_deg = 16.0;  // the panels' texels (TrialScene::build)
};

struct ViewedScene {
  geometry::Space space;
  std::optional<geometry::TableShape> table;  // the table scenes'
  renderer::Scene scene;
  geometry::Isometry head;  // where the viewer's nose is
  Placement placement;      // the stimulus as placed at onset
};

// Settings that give no table are bad_input; a prompt font that cannot be
// read, io.
Result<ViewedScene> viewed_scene(SceneKind kind, const protocol::Settings& s, const SceneView& view,
                                 const std::string& prompt, const std::string& font_path);

}  // namespace curvlab::harness::runner
